"""Shared tuning (`rvmsim tune SCENE1 SCENE2 --shared`): one setting that passes on two
vehicles where each one's own optimum fails the other; stored and resumable like any run;
status, select and report on it (small real renders, real searches)."""

from __future__ import annotations

import json
import signal
import sqlite3
from html.parser import HTMLParser

import pytest
import yaml

from rvmsim.criteria import default_criteria
from rvmsim.errors import RvmsimError
from rvmsim.pipeline import evaluate_params
from rvmsim.render import cached_render
from rvmsim.report import write_report
from rvmsim.scene import load_scene
from rvmsim.tune import TuneRequest, resume, tune
from rvmsim.search import TuningConfig
from rvmsim.runs import RunStore, rank_params_text, status_lines

from ..cli_runner import run_in_process, start_in_child
from .common import stored_trials, wait_for_trials
from rvmsim.testing.scenes import write_small_scene

CONFIG = {"output": {"size": [320, 180]}, "batch": 20}


@pytest.fixture(scope="module")
def scenes(cache, tmp_path_factory):
    """Vehicles E and B at 320×240 px, as scene files, each with a 320 × 180 display image
    (the RVM image of record: the verdicts are those of the search size, as these figures
    were found; at 1280 × 720 EC 3-1 keeps both from passing together, issue #30)."""
    folder = tmp_path_factory.mktemp("scenes")
    return [write_small_scene(folder, letter, edit={"display": {"rvm_image_px": [320, 180]}})
            for letter in "eb"]


def verdicts(params, scene_files):
    """Whether every EC passes on each scene, measured with the real evaluator."""
    out = []
    for f in scene_files:
        images, _ = cached_render(load_scene(f))
        frame = evaluate_params(images, params, TuningConfig.model_validate(CONFIG).output_spec(),
                                default_criteria(), annotate=False)
        out.append(frame.ec.passed)
    return out


#: Evaluations of the shared run.  B's small scene is B's camera resampled (its principal
#: point where ``render --scale 0.25`` puts it, 0.375 px from where cx/4, cy/4 put it):
#: after 1,000 evaluations the default seed's best fails B's 1-4 (score 0.275); after 3,000
#: it passes both (0.352 on E, 0.358 on B).
SHARED_BUDGET = 3000


@pytest.fixture(scope="module")
def shared_run(scenes, tmp_path_factory):
    run = tmp_path_factory.mktemp("runs") / "shared"
    res = tune(TuneRequest(tuple(scenes), config=TuningConfig.model_validate(CONFIG),
                           budget=SHARED_BUDGET), run)
    return run, res


def test_shared_tuning_passes_both_where_each_alone_fails_the_other(scenes, shared_run,
                                                                     tmp_path):
    cfg = TuningConfig.model_validate(CONFIG)
    alone = [tune(TuneRequest((s,), config=cfg, budget=1000), tmp_path / s.stem).outcome.best
             for s in scenes]
    # each vehicle's own optimum passes on it and fails on the other
    assert verdicts(alone[0].params, scenes) == [True, False]
    assert verdicts(alone[1].params, scenes) == [False, True]
    run, res = shared_run
    best = res.outcome.best
    assert verdicts(best.params, scenes) == [True, True]
    assert best.passed
    doc = json.loads((run / "best" / "members.json").read_text())
    assert [m["vehicle"] for m in doc["members"]] == [load_scene(s).name for s in scenes]
    assert doc["ec_score"] == pytest.approx(min(m["ec_score"] for m in doc["members"]))


def test_a_shared_run_records_its_scenes_and_refuses_a_changed_one(scenes, shared_run,
                                                                   tmp_path):
    run, _ = shared_run
    store = RunStore(run / "run.sqlite", readonly=True)
    s = store.settings()
    store.close()
    assert s is not None and s.shared and s.kind.aggregate == "min"
    assert [r.scene for r in s.scenes] == [str(f.resolve()) for f in scenes]
    assert s.scene == s.scenes[0].scene
    assert json.loads((run / "run.json").read_text())["scenes"][1]["vehicle"] == \
        load_scene(scenes[1]).name
    # status and select read it
    lines = status_lines(run)
    assert "shared by 2 scenes" in lines[1]
    store = RunStore(run / "run.sqlite", readonly=True)
    best = store.top(1)[0]
    each = [m[0] for m in store.member_results(best.idx)]
    store.close()
    first = next(ln for ln in lines if ln.startswith("  #1 "))
    assert first.endswith("[" + ", ".join(f"{m:.4g}" for m in each) + "]")
    assert "rank 1" in rank_params_text(run)
    # the diverse top-M of a shared run: top/, status and select agree
    from rvmsim.runs import diverse_candidates

    cands = diverse_candidates(run)
    listed = json.loads((run / "top" / "candidates.json").read_text())["candidates"]
    assert [c["trial"] for c in listed] == [c.trial for c in cands]
    assert [ln for ln in lines if ln.startswith("  #")][-1].split()[0] == f"#{len(cands)}"
    assert f"(trial {cands[-1].trial}," in rank_params_text(run, len(cands))
    # a changed second scene: resume refuses, naming it
    copy = tmp_path / "copy"
    folder = tmp_path / "scenes"
    folder.mkdir()
    files = [write_small_scene(folder, letter) for letter in "eb"]
    tune(TuneRequest(tuple(files), config=TuningConfig.model_validate(CONFIG), budget=40), copy)
    doc = yaml.safe_load(files[1].read_text())
    doc["vehicle"]["bumper"]["top"] = 0.8
    files[1].write_text(yaml.safe_dump(doc))
    with pytest.raises(RvmsimError, match="vehicle_b.yaml: the scene changed"):
        resume(copy)


class _Rows(HTMLParser):
    """The rows of the report's members table: their cell texts."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[list[str]] = []
        self.section = False
        self.cell: list[str] | None = None
        self.scores = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "section":
            self.section = a.get("id") == "members"
        if self.section and tag == "tr" and a.get("class") == "member":
            self.rows.append([])
        if self.section and tag == "td" and self.rows:
            self.cell = []
        if tag == "img" and self.section and self.rows:
            self.rows[-1].append("<img>")
        if tag == "ul" and a.get("class") == "member-scores":
            self.scores += 1

    def handle_data(self, data):
        if self.cell is not None:
            self.cell.append(data)

    def handle_endtag(self, tag):
        if tag == "td" and self.cell is not None:
            self.rows[-1].append(" ".join(self.cell).strip())
            self.cell = None
        if tag == "section":
            self.section = False


def test_the_report_has_a_row_per_vehicle(scenes, shared_run, tmp_path):
    run, res = shared_run
    html = write_report(run, tmp_path / "report.html").read_text()
    p = _Rows()
    p.feed(html)
    names = [load_scene(s).name for s in scenes]
    assert len(p.rows) == 2
    for row, name, ok in zip(p.rows, names, verdicts(res.outcome.best.params, scenes)):
        assert row[0].startswith(name)
        assert "<img>" in row
        score, *cells = [c for c in row[row.index("<img>") + 1:] if c]  # after the thumbnail
        assert float(score) > 0
        assert len(cells) == 11 and (all(c == "pass" for c in cells) == ok)
    # every top-M card shows the vehicles' scores
    store = RunStore(run / "run.sqlite", readonly=True)
    assert p.scores == len(store.top(TuningConfig.model_validate(CONFIG).top_m))
    store.close()


@pytest.mark.slow  # one path resumes every kind (tune/run.py): a robust run, a multi-member
# kind too, resumes after SIGKILL in tests/tune/test_robust.py, a single one in test_run.py
def test_a_shared_run_resumes_after_sigkill_to_the_unbroken_result(scenes, tmp_path):
    cfg = tmp_path / "tune.yaml"
    cfg.write_text(yaml.safe_dump({**CONFIG, "cmaes_solved": {"budget": 1000}}))

    def cmd(out, *extra):
        if extra:
            return ["tune", *extra, "--no-progress", "--workers", "1"]
        return ["tune", *scenes, "--shared", "--out", out, "--config", cfg, "--no-progress",
                "--workers", "1"]

    clean = run_in_process(cmd(tmp_path / "clean"))
    doc = json.loads((tmp_path / "clean" / "best" / "members.json").read_text())
    every = all(m["passed"] for m in doc["members"])
    # exit 1 when no setting passes every scene (issue #30), saying which ECs fail where
    assert clean.code == (0 if every else 1), clean.stderr
    assert every or "no setting found passes every scene" in clean.stdout
    run = tmp_path / "killed"
    proc = start_in_child(cmd(run))
    db = run / "run.sqlite"
    wait_for_trials(db, 200)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    con = sqlite3.connect(db)
    stored = con.execute("SELECT COUNT(*) FROM trials").fetchone()[0]
    members = con.execute("SELECT COUNT(*) FROM members").fetchone()[0]
    con.close()
    assert 200 <= stored < 1000, stored
    assert members == 2 * stored  # each trial's members written with it
    resumed = run_in_process(cmd(None, "--resume", run))
    assert resumed.code == clean.code, resumed.stderr
    assert "replayed" in resumed.stdout

    assert stored_trials(run) == stored_trials(tmp_path / "clean")
    assert (run / "best" / "members.json").read_text() == \
        (tmp_path / "clean" / "best" / "members.json").read_text()
