"""The diverse top-M on a real small tuning run (320×240 scene, the default search with a
few hundred evaluations): the rule's guarantees recomputed from the run's trials, and top/,
candidates.json, ``rvmsim status``, ``rvmsim select`` and the report offering one list."""

from __future__ import annotations

import itertools
import json
import re

import numpy as np
import pytest

from rvmsim.isp import load_params
from rvmsim.scene import load_scene
from rvmsim.tune import TuneRequest, tune
from rvmsim.search import TuningConfig
from rvmsim.runs import RunStore, diverse_candidates, rank_params_text, status_lines

from ..cli_runner import run_in_process
from rvmsim.testing.scenes import write_small_scene

CONFIG = {"output": {"size": [320, 180]}, "top_m": 10, "batch": 50,
          "diverse": {"min_distance": 0.08}}


@pytest.fixture(scope="module")
def run(cache, tmp_path_factory):
    folder = tmp_path_factory.mktemp("diverse")
    scene = write_small_scene(folder, "a")
    out = folder / "run"
    tune(TuneRequest((scene,), config=TuningConfig.model_validate(CONFIG), budget=300), out)
    return out


def _spans(run):
    """Low ends and spans of the tuned parameters, from the config on the scene's camera
    (not from what the run recorded)."""
    settings = json.loads((run / "run.json").read_text())
    space = TuningConfig.model_validate(settings["config"]).space(
        load_scene(settings["scene"]).fisheye_camera())
    return space, space.low, space.high - space.low


def _trials(run):
    store = RunStore(run / "run.sqlite", readonly=True)
    try:
        return store.trials()
    finally:
        store.close()


def test_the_candidates_are_apart_pass_and_start_with_the_best(run):
    space, low, span = _spans(run)
    trials = _trials(run)
    cands = diverse_candidates(run)
    assert 2 <= len(cands) <= 10

    def norm(p):
        return (space.vector(p) - low) / span

    for a, b in itertools.combinations(cands, 2):
        assert np.linalg.norm(norm(a.params) - norm(b.params)) >= 0.08
    best = max(trials, key=lambda t: (t.score, t.objective, -t.idx))
    assert cands[0].trial == best.idx and cands[0].params == best.params
    passers = [t for t in trials if t.passed]
    for k, c in enumerate(cands[1:], start=1):
        if c.pool == "all-pass":
            assert c.passed
        else:  # only once no passer is left far enough from those chosen before
            assert not c.passed
            assert not any(all(np.linalg.norm(norm(t.params) - norm(p.params)) >= 0.08
                               for p in cands[:k]) for t in passers)
            if c.pool == "score-tolerance":
                assert c.score >= 0.98 * best.score
        assert c.differs and c.distance == pytest.approx(
            float(np.linalg.norm(norm(c.params) - norm(best.params))))
    # a larger minimum distance: fewer or as many, all that far apart
    wide = diverse_candidates(run, min_distance=0.3)
    assert len(wide) <= len(cands) and wide[0] == cands[0]
    for a, b in itertools.combinations(wide, 2):
        assert np.linalg.norm(norm(a.params) - norm(b.params)) >= 0.3
    # a smaller M is the start of the same list
    assert diverse_candidates(run, 3) == cands[:3]
    # the plain order, on request
    plain = diverse_candidates(run, 4, by_score=True)
    by_score = sorted(trials, key=lambda t: (-t.score, -t.objective, t.idx))[:4]
    assert [c.trial for c in plain] == [t.idx for t in by_score]


def test_top_files_status_select_and_report_offer_the_same_list(run, tmp_path):
    from rvmsim.report import write_report

    cands = diverse_candidates(run)
    doc = json.loads((run / "top" / "candidates.json").read_text())
    assert doc["rule"] == "diverse" and doc["min_distance"] == 0.08 and doc["m"] == 10
    assert [(c["rank"], c["trial"], c["differs"]) for c in doc["candidates"]] == \
        [(c.rank, c.trial, c.differs) for c in cands]
    assert sorted(p.name for p in (run / "top").glob("rank_*.yaml")) == \
        sorted(f"rank_{c.rank}.yaml" for c in cands)
    for c in cands:
        path = run / "top" / f"rank_{c.rank}.yaml"
        assert load_params(path)[0] == c.params
        assert doc["candidates"][c.rank - 1]["params"] == {
            k: getattr(c.params, k) for k in doc["candidates"][c.rank - 1]["params"]}
        if c.rank > 1:
            assert path.read_text(encoding="utf-8").splitlines()[1] == \
                f"# differs from rank 1: {c.differs}"
    # status: one line per candidate, in the same order
    lines = status_lines(run)
    ranks = [ln for ln in lines if ln.startswith("  #")]
    assert [int(re.search(r"trial +(\d+)", ln).group(1)) for ln in ranks] == \
        [c.trial for c in cands]
    assert all(c.differs in ln for c, ln in zip(cands[1:], ranks[1:]))
    # select --rank K (the CLI) writes rank K's file
    k = min(3, len(cands))
    sel = run_in_process(["select", run, "--rank", k, "--out", tmp_path / "k.yaml"])
    assert sel.code == 0, sel.stderr
    written = (tmp_path / "k.yaml").read_text(encoding="utf-8").splitlines()
    assert written[0].startswith(f"# rank {k}: ")  # the top file names the vehicle too
    assert written[1:] == (run / "top" / f"rank_{k}.yaml").read_text(
        encoding="utf-8").splitlines()[1:]
    assert rank_params_text(run, k) == (tmp_path / "k.yaml").read_text(encoding="utf-8")
    st = run_in_process(["status", run, "--top", "2", "--by-score"])
    assert st.code == 0 and st.stdout.splitlines() == status_lines(run, 2, by_score=True)
    # the report's gallery: the same candidates, each card with its differs line
    page = write_report(run, tmp_path / "r.html").read_text(encoding="utf-8")
    gallery = page[page.index('id="gallery"'):]
    cards = re.findall(r'id="rank-(\d+)".*?trial (\d+) ', gallery)
    assert [(int(a), int(b)) for a, b in cards] == [(c.rank, c.trial) for c in cands]
    import html

    for c in cands[1:]:
        assert html.escape(c.differs) in gallery


def test_the_diverse_section_of_the_config_sets_m_and_the_distance(run, tmp_path):
    cfg = TuningConfig.model_validate({**CONFIG, "output": {"size": [160, 90]},
                                       "diverse": {"m": 4, "min_distance": 0.2}})
    assert cfg.diverse_m == 4 and TuningConfig().diverse_m == 10
    small = tmp_path / "small"
    tune(TuneRequest((write_small_scene(tmp_path, "a"),), "random", cfg, seed=1, budget=60),
         small)
    cands = diverse_candidates(small)
    assert 2 <= len(cands) <= 4
    assert sorted(p.name for p in (small / "top").iterdir()) == sorted(
        [f"rank_{c.rank}.yaml" for c in cands] + ["candidates.json"])
    space, low, span = _spans(small)
    for a, b in itertools.combinations(cands, 2):
        assert np.linalg.norm((space.vector(a.params) - space.vector(b.params)) / span) >= 0.2
    # M and the distance given on the command line replace the run's
    five = run_in_process(["status", run, "--top", "5", "--min-distance", "0.2"])
    assert five.code == 0, five.stderr
    assert five.stdout.splitlines() == status_lines(run, 5, min_distance=0.2)
    assert len([ln for ln in five.stdout.splitlines() if ln.startswith("  #")]) == \
        len(diverse_candidates(run, 5, 0.2))
