"""Bundled criteria sets by name (`fmvss111-full`), EC parameters and the `display` section
of criteria files."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import EC_IDS, SceneContext, criteria_reference, load_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.errors import CriteriaError
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.scene import Display

from ..conftest import SCENES
from ..regulations.test_fmvss111 import level_scene, pinhole_params

NEW = ("1-5", "1-6", "6-1")


def test_fmvss111_full_is_the_paper_eleven_and_three():
    crit = load_criteria("fmvss111-full")
    assert crit.ids == EC_IDS + NEW
    assert crit.name == "fmvss111-full"
    assert all(crit.items[ec].enabled for ec in crit.ids)


def test_a_file_of_that_name_wins(tmp_path, monkeypatch):
    (tmp_path / "fmvss111-full").write_text("name: mine\necs: [1-1]\n")
    monkeypatch.chdir(tmp_path)
    assert load_criteria("fmvss111-full").ids == ("1-1",)


def test_a_misspelt_name_is_one_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(CriteriaError, match="fmvss111-full") as err:
        load_criteria("fmvss111-ful")
    assert "\n" not in str(err.value)


def test_runs_record_a_name_as_given_and_a_file_absolute(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.yaml").write_text("name: c\n")
    assert criteria_reference("fmvss111-full") == "fmvss111-full"
    assert criteria_reference("c.yaml") == str(tmp_path / "c.yaml")


def test_parameters_and_display_of_a_criteria_file(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("plugins: [rvmsim.regulations.fmvss111.ecs]\n"
                    "display: {eye_distance_mm: 500, width_mm: 200}\n"
                    "criteria:\n  6-1: {parameters: {max_magnification: 4.0}}\n")
    crit = load_criteria(path)
    assert crit.ids == EC_IDS + NEW
    opts = crit.options
    assert opts.parameter("6-1", "max_magnification", 0.0) == 4.0
    assert opts.parameter("6-1", "min_pixels_per_degree", 0.0) == 2.0  # the default
    assert opts.display == Display(eye_distance_mm=500, width_mm=200)
    # the measurements follow: the magnification limit doubles the zoom margin, and the
    # closer eye and wider display change the visual angles as the formula says
    scene = level_scene((0.0, 6.1))
    cam = scene.fisheye_camera()
    labels = np.zeros((cam.height, cam.width), np.uint8)
    out = OutputSpec(640, 480)
    params = pinhole_params(3.0)  # zoomed in: the magnification limit binds
    base = CandidateEvaluator(labels, out, load_criteria("fmvss111-full"), scene=scene)
    mine = CandidateEvaluator(labels, out, crit, scene=scene)
    w0, w1 = base.measure(params), mine.measure(params)
    mag = w0.details["6-1"]["B"]["magnification"]
    assert 2.0 / mag < 1.0
    assert w1.details["6-1"]["B"]["magnification"] == mag
    assert w1.values["6-1"] / w0.values["6-1"] == pytest.approx(2.0, rel=1e-9)
    assert w1.details["1-6"]["B"]["mm"] == pytest.approx(w0.details["1-6"]["B"]["mm"] * 200
                                                         / Display().width_mm)


def test_a_scenes_display_wins_over_the_criteria_files():
    scene = level_scene(display={"eye_distance_mm": 640.0})
    cam = scene.fisheye_camera()
    ctx = SceneContext(scene, cam, np.zeros((cam.height, cam.width), np.uint8))
    assert ctx.display(Display(eye_distance_mm=500.0)).eye_distance_mm == 640.0
    plain = level_scene()
    ctx = SceneContext(plain, cam, np.zeros((cam.height, cam.width), np.uint8))
    assert ctx.display(Display(eye_distance_mm=500.0)).eye_distance_mm == 500.0
    assert ctx.display().eye_distance_mm == Display().eye_distance_mm


def test_a_sweep_file_names_the_set(tmp_path):
    from rvmsim.batch import load_sweep

    sweep = tmp_path / "s.yaml"
    sweep.write_text(f"name: s\nbase_scene: {SCENES / 'vehicle_a.yaml'}\n"
                     "axes: {pitch_deg: [30, 32]}\n"
                     "tune: {budget: 10, criteria: fmvss111-full}\n")
    spec = load_sweep(sweep)
    assert spec.criteria().ids == EC_IDS + NEW


def test_plugin_ecs_unpickle_in_workers():
    import pickle

    crit = load_criteria("fmvss111-full")
    scene = level_scene()
    cam = scene.fisheye_camera()
    ev = CandidateEvaluator(np.zeros((cam.height, cam.width), np.uint8), OutputSpec(320, 240),
                            crit, scene=scene)
    p = IspParams(fov=180.0, rad=612.6, zoom=1.0)
    again = pickle.loads(pickle.dumps(ev))
    assert np.array_equal(again.values(p), ev.values(p), equal_nan=True)


def test_a_criteria_file_naming_a_plugin_where_it_used_to_be_still_loads(tmp_path):
    """Criteria files (and the runs that recorded them) from before the regulations moved
    name ``rvmsim.criteria.fmvss111``: they load the same ECs from the new home."""
    old, new = tmp_path / "old.yaml", tmp_path / "new.yaml"
    old.write_text("plugins: [rvmsim.criteria.fmvss111]\n")
    new.write_text("plugins: [rvmsim.regulations.fmvss111.ecs]\n")
    assert load_criteria(old).ids == load_criteria(new).ids == EC_IDS + NEW
