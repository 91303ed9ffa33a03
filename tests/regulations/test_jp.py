"""Japan's ECs (rvmsim/regulations/jp/ecs.py) on a small real render of vehicle A at the jp site:
JP-3 is the shown square alone (no top alternative), JP-4 passes when any part shows."""

from __future__ import annotations

import functools

import pytest

from rvmsim.criteria import load_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.regulations.jp.ecs import ADJACENT_AREA_M, PROXIMITY_LEAST_PERCENT
from rvmsim.regulations.siteobjects import SAMPLE_STEP_M, shown_area
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.pipeline import evaluate_params
from rvmsim.render import render_fisheye
from rvmsim.scene import site_scene

from rvmsim.testing.scenes import load_small_scene

OUT = OutputSpec(320, 180)


@functools.lru_cache(maxsize=None)
def _at_jp():
    at = site_scene(load_small_scene("a"), "jp")
    return at, render_fisheye(at)


def _judge(v_shift: float):
    """The jp ECs of a view moved up by ``v_shift`` output half-heights (the near poles
    leave the image at its bottom edge)."""
    _, images = _at_jp()
    params = IspParams(fov=180.0, rad=160.0, zoom=0.45, adv_v_shift=v_shift)
    return evaluate_params(images, params, OUT, load_criteria("jp"), annotate=False).ec


@pytest.mark.parametrize("v_shift", [0.15, -0.4, -0.5])
def test_jp3_is_the_square_alone(v_shift):
    ec = _judge(v_shift)
    margins = ec.measurements.details["JP-3"][0]
    assert sorted(margins) == ["adjacent.1", "adjacent.2"]
    cell = SAMPLE_STEP_M / ADJACENT_AREA_M  # one sample step of the square, in the margin
    for value in margins.values():
        # a whole number of sample steps: a top fraction never enters the figure
        assert value / cell == pytest.approx(round(value / cell), abs=1e-9)
    assert ec["JP-3"].value == min(margins.values())
    assert ec["JP-3"].passed == (ec["JP-3"].value >= 1.0)


def test_jp3_reads_the_square_of_the_shown_area_never_its_top():
    # the adjacent poles cut by the bottom edge: under 0.2 m of square left
    ec = _judge(-0.4)
    assert not ec["JP-3"].passed and 0.0 < ec["JP-3"].value < 1.0
    at, images = _at_jp()

    ev = CandidateEvaluator(images.labels, OUT, load_criteria("jp"), scene=at,
                            camera=images.camera)
    src = ev.source(IspParams(fov=180.0, rad=160.0, zoom=0.45, adv_v_shift=-0.4))
    for name in ("adjacent.1", "adjacent.2"):
        shown = shown_area(src, name)
        assert shown is not None and shown.top_fraction > 0.0
        margin = ec.measurements.details["JP-3"][0][name]
        assert margin == shown.square_m / ADJACENT_AREA_M < 1.0


@pytest.mark.parametrize("v_shift", [0.15, -0.4, -0.5, -0.75])
def test_jp4_passes_when_any_part_shows(v_shift):
    ec = _judge(v_shift)
    shown = ec.measurements.details["JP-4"][0]
    assert sorted(shown) == ["proximity.1", "proximity.2", "proximity.3"]
    least = min(shown.values())
    assert ec["JP-4"].value == least
    assert ec["JP-4"].passed == (least >= PROXIMITY_LEAST_PERCENT)
    if v_shift in (-0.4, -0.5):  # most of a pole cut off, a part still shown: passes
        assert PROXIMITY_LEAST_PERCENT <= least < 60.0 and ec["JP-4"].passed
        # where R158-2/3's rule (the whole cylinder) fails
        assert ec["JP-1"].passed
