"""Robust tuning (``tune --robust``): a setting tuned on variation samples has a higher
yield, measured on fresh samples by ``robustness``, than one tuned on the nominal scene;
its store and results say nominal score, robust score and yield; it resumes after SIGKILL."""

from __future__ import annotations

import json
import os
import signal
import sqlite3
import time

import numpy as np
import pytest

from rvmsim.scene import load_scene
from rvmsim.tune import Robust, TuneRequest, member_set, tune
from rvmsim.search import TuningConfig
from rvmsim.runs import RunStore

from ..cli_runner import run_in_process, start_in_child
from rvmsim.testing.scenes import write_small_scene

CONFIG = {"output": {"size": [320, 180]}, "top_m": 3}


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    folder = tmp_path_factory.mktemp("robust")
    old = os.environ.get("RVMSIM_CACHE")
    os.environ["RVMSIM_CACHE"] = str(folder / "cache")
    # a 320 × 180 RVM image of record: the figures below are those of that display
    yield write_small_scene(folder, name="scene.yaml",
                            edit={"display": {"rvm_image_px": [320, 180]}})
    if old is None:
        os.environ.pop("RVMSIM_CACHE", None)
    else:
        os.environ["RVMSIM_CACHE"] = old


def _best(run):
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        return store.top(1)[0]
    finally:
        store.close()


def _best_members(run_dir):
    """(the run's best record, its members' results, the run's settings), read-only."""
    store = RunStore(run_dir / "run.sqlite", readonly=True)
    try:
        rec = store.top(1)[0]
        return rec, store.member_results(rec.idx), store.settings()
    finally:
        store.close()


@pytest.mark.slow  # two tunes and two yields of 200 samples
def test_robust_tuning_raises_the_yield_on_fresh_samples(small, tmp_path):
    from rvmsim.isp import OutputSpec
    from rvmsim.robust import RobustnessSettings, robustness

    cfg = TuningConfig.model_validate(CONFIG)
    nominal = tune(TuneRequest((small,), config=cfg, budget=600, seed=1), tmp_path / "nominal")
    tune(TuneRequest((small,), config=cfg, budget=600, seed=1, kind=Robust(8)),
         tmp_path / "robust")
    out = OutputSpec(320, 180)
    scene = load_scene(small)
    # judged on 48 samples the runs never saw (another seed)
    fresh = RobustnessSettings(out, samples=48, seed=77, scales=(1.0,))
    y_nom = robustness(scene, _best(tmp_path / "nominal").params, fresh)
    y_rob = robustness(scene, _best(tmp_path / "robust").params, fresh)
    assert y_rob.estimate.yield_ > y_nom.estimate.yield_
    assert nominal.outcome.best.passed  # the nominal setting passes where it was tuned
    doc = json.loads((tmp_path / "robust" / "best" / "robust.json").read_text())
    top = doc["top"][0]
    assert doc["samples_per_scene"] == 8 and top["samples"] == 8
    assert top["robust_score"] <= top["nominal_score"]  # a low quantile, nominal included
    assert 0.0 <= top["yield_ci"][0] <= top["yield"] <= top["yield_ci"][1] <= 1.0
    # its rows are the diverse top-M of top/ (rank for rank)
    listed = json.loads((tmp_path / "robust" / "top" / "candidates.json").read_text())
    assert [(r["rank"], r["trial"]) for r in doc["top"]] == \
        [(c["rank"], c["trial"]) for c in listed["candidates"]]
    # the stored members: the nominal image, then the 8 samples
    rec, members, settings = _best_members(tmp_path / "robust")
    # the robust score is the members' 10 % quantile (the default), here the lowest of nine
    assert len(members) == 9 and rec.score == pytest.approx(
        float(np.quantile([m[0] for m in members], 0.1, method="lower")))
    assert settings.kind.aggregate == "quantile 0.1"
    assert settings.kind.robust is not None
    assert settings.kind.robust.samples == 8 and settings.kind.robust.variation_key
    # the report puts nominal score, robust score and yield side by side
    from rvmsim.report import write_report

    html = write_report(tmp_path / "robust").read_text()
    section = html[html.index('<section id="robust">'):]
    section = section[:section.index("</section>")]
    assert section.count("<tr>") == 1 + 3  # header + the top 3
    assert f"{top['nominal_score']:.4g}" in section and f"{top['robust_score']:.4g}" in section


def test_a_robust_run_resumes_after_sigkill_to_the_unbroken_result(small, tmp_path):
    env = {"RVMSIM_CACHE": os.environ["RVMSIM_CACHE"]}
    cfg = tmp_path / "tune.yaml"
    cfg.write_text(json.dumps({**CONFIG, "cmaes_solved": {"budget": 700}}))

    def cmd(out, *extra):
        if extra:
            return ["tune", "--no-progress", "--workers", "1", *extra]
        return ["tune", small, "--robust", "--samples", "4", "--config", cfg, "--out", out,
                "--workers", "1", "--no-progress"]

    clean = run_in_process(cmd(tmp_path / "clean"), env=env)
    assert clean.code == 0, clean.stderr
    run = tmp_path / "killed"
    proc = start_in_child(cmd(run), env=env)
    db = run / "run.sqlite"
    deadline = time.time() + 600
    while time.time() < deadline:
        try:
            if db.exists() and sqlite3.connect(db).execute(
                    "SELECT COUNT(*) FROM trials").fetchone()[0] >= 150:
                break
        except sqlite3.Error:
            pass
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    stored = sqlite3.connect(db).execute("SELECT COUNT(*) FROM trials").fetchone()[0]
    assert 150 <= stored < 700
    resumed = run_in_process(cmd(None, "--resume", run), env=env)
    assert resumed.code == 0, resumed.stderr

    def top(path):
        s = RunStore(path / "run.sqlite", readonly=True)
        try:
            return [(r.idx, r.params, r.score) for r in s.top(3)], s.count(), \
                [s.member_results(r.idx) for r in s.top(3)]
        finally:
            s.close()

    assert top(run) == top(tmp_path / "clean")


def test_shared_and_robust_together_judge_every_scene_on_its_own_samples(small, tmp_path):
    """`--shared --robust`: each scene brings its nominal image and its samples; the stored
    members are scene by scene, and robust.json has each scene's nominal score."""
    import shutil

    sub = tmp_path / "variant"
    sub.mkdir()
    other = write_small_scene(sub, edit={"vehicle.bumper.top": 0.8})
    shutil.copy(other, tmp_path / "b.yaml")
    cfg = TuningConfig.model_validate(CONFIG)
    run = tmp_path / "both"
    tune(TuneRequest((small, tmp_path / "b.yaml"), config=cfg, budget=60, seed=2,
                     kind=Robust(3)), run)
    rec, members, settings = _best_members(run)
    assert settings.shared and settings.kind.robust is not None
    assert settings.kind.robust.samples == 3
    assert len(members) == 2 * (1 + 3)
    doc = json.loads((run / "best" / "robust.json").read_text())
    top = doc["top"][0]
    assert top["samples"] == 6 and len(top["nominal_scores"]) == 2
    # the nominal scores are the first member of each scene's block
    assert top["nominal_scores"] == pytest.approx([members[0][0], members[4][0]])
    # what the run's kind tells the report of its top candidates: every member's score and
    # the robust summary robust.json holds
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        best = store.top(3)
        rows = member_set(store.settings()).top_rows(store, best)
    finally:
        store.close()
    assert rows.member_scores[rec.idx] == pytest.approx([m[0] for m in members])
    assert len(rows.robust) == len(best) and best[0].idx == rec.idx == top["trial"]
    assert rows.robust[0]["nominal_scores"] == pytest.approx(top["nominal_scores"])
    assert rows.robust[0]["yield"] == pytest.approx(top["yield"])


#: ±2.5° on every angle: no setting passes a tenth of the samples, so the 10 % quantile of
#: their EC scores (the robust aggregate) is flat at ~0.
WIDE = {"mount": {a: {"uniform": {"half_width": 2.5}} for a in ("yaw_deg", "pitch_deg",
                                                               "roll_deg")}}


def test_a_flat_robust_aggregate_ranks_by_the_nominal_car_then_the_yield(tmp_path):
    """Where the aggregate carries no ranking, rank 1 is a setting that passes the car as
    designed (when one was evaluated), the one of those with the highest yield over the
    samples; the run says that this yield is one setting's without end-of-line
    compensation, naming the EC."""
    from rvmsim.runs import FLAT_SCORE

    scene = write_small_scene(tmp_path, name="wide.yaml", variation=WIDE,
                              edit={"display": {"rvm_image_px": [320, 180]}})
    cfg = tmp_path / "cfg.yaml"
    cfg.write_text(json.dumps(CONFIG))
    run = tmp_path / "run"
    res = run_in_process(["tune", str(scene), "--robust", "--samples", "6", "--budget", "160",
                          "--seed", "2", "--config", str(cfg), "--workers", "1", "--out",
                          str(run), "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    assert res.code in (0, 1), res.stderr
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        idx, member, score, passed = store.member_table()
        trial_scores = dict(store.rows("SELECT idx, score FROM trials"))
    finally:
        store.close()
    per = 1 + 6
    nominal_pass = {int(i) for i, m, p in zip(idx, member, passed) if m % per == 0 and p}
    assert max(trial_scores.values()) < FLAT_SCORE, "the aggregate was not flat"
    assert nominal_pass, "no trial passed the nominal car: nothing to rank by"
    yields = {}
    for i, m, p in zip(idx, member, passed):
        if m % per:
            yields.setdefault(int(i), []).append(bool(p))
    best = json.loads((run / "best" / "ec.json").read_text())["trial"]
    assert best in nominal_pass
    assert np.mean(yields[best]) == max(np.mean(yields[i]) for i in nominal_pass)
    assert "without end-of-line compensation: EC " in res.stdout, res.stdout
    assert f"(trial {best})" in res.stdout
