"""Opening a console session on a run or a scene, and one setting's evaluation."""

from __future__ import annotations

import shutil

import pytest

from rvmsim.console import evaluate_setting, open_session
from rvmsim.errors import RvmsimError
from rvmsim.isp import PARAM_SPECS, IspParams, TUNED_BY_DEFAULT
from rvmsim.markets import market_members, parse_markets
from rvmsim.runs import open_run
from rvmsim.scene import load_scene
from rvmsim.search import TuningConfig
from rvmsim.testing.scenes import write_small_scene
from rvmsim.tune import Markets, TuneRequest, tune


def test_a_run_starts_at_rank_1_with_its_candidates(small_run):
    s = open_session(small_run / "run")
    store = open_run(small_run / "run")
    try:
        top = store.top(10)
    finally:
        store.close()
    assert s.kind == "run" and s.start == top[0].params
    assert [c.trial for c in s.candidates] == [r.idx for r in top]
    assert s.save_dir == small_run / "run" / "console" and s.root == small_run / "run"
    # judged (and shown) at the RVM image of record, whatever size the run searched at
    assert (s.ec_output.width, s.ec_output.height) == (1280, 720)
    assert (s.display.width, s.display.height) == (1280, 720)
    names = [c.name for c in s.controls]
    assert sorted(names) == sorted(p.name for p in PARAM_SPECS)
    assert names[:len(TUNED_BY_DEFAULT)] == list(TUNED_BY_DEFAULT)
    zoom = next(c for c in s.controls if c.name == "zoom")
    assert zoom.tuned and (zoom.low, zoom.high) == (0.25, 1.45)
    tilt = next(c for c in s.controls if c.name == "tilt")
    assert not tilt.tuned and (tilt.low, tilt.high) == (-180.0, 180.0)


def test_a_scene_starts_at_the_papers_defaults(small_run, tmp_path):
    s = open_session(small_run / "scene.yaml", out_root=tmp_path / "out")
    assert s.kind == "scene" and s.start == IspParams() and s.candidates == ()
    assert s.save_dir == tmp_path / "out" / "scene" / "console"
    assert not s.save_dir.exists()  # nothing written before a save


def test_missing_and_wrong_sources_are_one_line_errors(tmp_path):
    from rvmsim.tune import TuneRequest, tune
    from rvmsim.testing.scenes import write_small_scene

    with pytest.raises(RvmsimError, match="no such run folder or scene file"):
        open_session(tmp_path / "nope")
    (tmp_path / "empty").mkdir()
    with pytest.raises(RvmsimError, match="not a run folder"):
        open_session(tmp_path / "empty")
    scene = write_small_scene(tmp_path, name="scene.yaml")
    tune(TuneRequest((scene,), "random", budget=4), tmp_path / "run")
    shutil.move(scene, tmp_path / "elsewhere.yaml")
    with pytest.raises(RvmsimError, match="scene file .* not found"):
        open_session(tmp_path / "run")


def test_the_ecs_change_with_the_zoom(small_run):
    s = open_session(small_run / "run")
    a = evaluate_setting(s, s.start)
    b = evaluate_setting(s, s.start.replace(zoom=s.start.zoom * 1.5))
    assert a.ec.as_dict() != b.ec.as_dict()
    assert a.display_jpeg != b.display_jpeg and a.roi != b.roi
    assert set(a.timings_ms) == {"ecs", "display", "annotated", "roi"}


def test_a_run_tuned_with_a_bundled_criteria_set_opens(tmp_path):
    """A run records a bundled set by its name (``fmvss111-full``), not as a file: the
    console finds it as ``report`` does, with the run's 14 ECs."""
    from rvmsim.tune import TuneRequest, tune
    from rvmsim.testing.scenes import write_small_scene

    scene = write_small_scene(tmp_path, name="scene.yaml")
    tune(TuneRequest((scene,), "random", criteria_file="fmvss111-full", budget=4),
         tmp_path / "run")
    s = open_session(tmp_path / "run")
    assert s.kind == "run" and len(s.criteria.ids) == 14 and "6-1" in s.criteria.ids
    assert s.candidates and s.start == s.candidates[0].params


def test_a_markets_run_is_shown_as_its_first_market_judges_it(tmp_path):
    """A markets run whose first market is UN R158: the console judges its candidates at
    R158's site by R158's criteria (the member its best/ shows), not by the paper's at the
    scene's own site."""
    scene_file = write_small_scene(tmp_path, edit={"display": {"rvm_image_px": [320, 180]}})
    config = TuningConfig.model_validate({"tuned": ["zoom", "adv_v_shift"],
                                          "output": {"size": [160, 90]}, "top_m": 3})
    tune(TuneRequest((scene_file,), "random", config, seed=1, budget=12,
                     kind=Markets(("unr158", "fmvss111"))), tmp_path / "run")
    s = open_session(tmp_path / "run")
    first = market_members([load_scene(scene_file)], parse_markets("unr158"))[0]
    assert list(s.criteria.ids) == list(first.criteria.ids)
    assert any(k.startswith("R158-") for k in s.criteria.ids)
    assert s.scene == first.scene and s.scene.test_site != load_scene(scene_file).test_site
    ecs = evaluate_setting(s, s.start).ec
    assert [v.id for v in ecs.items] == list(first.criteria.ids)
