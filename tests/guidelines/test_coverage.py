"""Which test objects' required-visible areas the guidelines are drawn over (FMVSS 111's and
UN R158's), read from the rendered label images."""

from __future__ import annotations

from rvmsim.guidelines import compute_guidelines, guideline_view
from rvmsim.guidelines.coverage import required_coverage
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.render import cached_render
from rvmsim.scene import GuidelineSpec
from rvmsim.testing.scenes import load_small_scene

SCALE = 0.25


def _covers(spec: dict[str, object], angles: tuple[float, ...] = (0.0,)):
    scene = load_small_scene("a", edit={"display": {"rvm_image_px": [320, 180]},
                                        "guidelines": spec})
    view = guideline_view(scene, IspParams(zoom=0.8).for_input_scale(SCALE), OutputSpec())
    gset = compute_guidelines(scene, view, angles)
    return required_coverage(scene, gset, cached_render(scene)[0].labels)


def test_a_mark_through_an_object_covers_it_and_lines_clear_of_them_cover_none() -> None:
    # width lines at ±(0.93 + 0.6) m from 2.5 m to 3.6 m run through D and E (3.05 m behind,
    # x = ±1.52 m); a mark across at 3.5 m through UN R158's row 3 (3.5 m, the car's sides
    # and centre)
    through = _covers({"marks": [{"distance": 3.5}],
                       "width_lines": {"margin": 0.6, "start": 2.5, "end": 3.6},
                       "trajectory": {"enabled": False}})
    assert {"D", "E"} <= set(through["fmvss111"])
    for name in ("D", "E"):
        v = through["fmvss111"][name]
        assert v["static_px"] > 0 and v["trajectory_px"] == {} and 0 < v["fraction"] <= 1
    # (row 3.2 stands behind row 2.2 in the picture, which the mark is drawn over instead)
    assert {"row3.1", "row3.3", "row2.2"} <= set(through["unr158"])
    # short lines near the car, between the objects: nothing covered
    clear = _covers({"marks": [{"distance": 0.1}], "width_lines": {"enabled": False},
                     "trajectory": {"enabled": False}})
    assert clear == {"fmvss111": {}, "unr158": {}}


def test_trajectories_are_reported_per_steering_angle() -> None:
    got = _covers({"marks": [{"distance": 0.1}], "width_lines": {"enabled": False},
                   "trajectory": {"travel": 6.0}}, angles=(0.0, 450.0))
    objs = {**got["fmvss111"], **{f"r158 {k}": v for k, v in got["unr158"].items()}}
    assert objs, "6 m of travel reaches objects"
    for v in objs.values():
        assert v["static_px"] == 0
        assert set(v["trajectory_px"]) <= {"0", "450"} and v["trajectory_px"]
    assert GuidelineSpec().trajectory.travel == 3.0  # the default is shorter
