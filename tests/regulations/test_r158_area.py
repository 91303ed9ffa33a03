"""R158-1 (row 1: a 0.15 m × 0.15 m area or the top of each cylinder shown) on small real
renders, against the geometry: the arc of a cylinder's side that faces a camera, the top
face seen from above, and the RVM image's border mapped point by point."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rvmsim.criteria import LabelSource, SceneContext, load_criteria
from rvmsim.criteria.context import IspView
from rvmsim.regulations.siteobjects import SAMPLE_STEP_M, shown_area, surface_view
from rvmsim.isp import IspParams, OutputSpec, input_to_output
from rvmsim.pipeline import evaluate_params
from rvmsim.render import render_fisheye
from rvmsim.scene import site_scene

from rvmsim.testing.scenes import load_small_scene

OUT = OutputSpec(320, 180)


@pytest.fixture(scope="module")
def low_body():
    """Vehicle A at the unr158 site with its bumper cut to 5 cm and no garnish or trunk:
    nothing hides row 1 but the cylinders' own far sides."""
    scene = load_small_scene("a", edit={"vehicle.bumper.top": 0.05, "vehicle.bumper.bottom": 0.0,
                                        "vehicle.garnish": None, "vehicle.trunk": None,
                                        "vehicle.width": 1.86})
    at = site_scene(scene, "unr158")
    images = render_fisheye(at)
    return at, images, SceneContext(at, images.camera, images.labels)


def _facing_arc_m(cam_xz: np.ndarray, obj) -> float:
    """Arc length (m) of a cylinder's side whose outward normal points to the camera's side
    of it: |azimuth − azimuth to the camera| < acos(r / horizontal distance)."""
    d = math.hypot(cam_xz[0] - obj.x, cam_xz[1] - obj.z)
    return 2.0 * obj.radius * math.acos(obj.radius / d)


def test_the_fisheye_shows_the_facing_arc_full_height_and_the_whole_top(low_body):
    """Upper bound over every setting (the whole fisheye): the largest shown square is the
    facing arc or the height, whichever is smaller, to a sample step; the camera above the
    cylinders sees their whole top."""
    at, images, ctx = low_body
    src = LabelSource(np.zeros((1, 1), np.uint8), context=ctx)
    cam_xz = images.camera.position[[0, 2]]
    assert -images.camera.position[1] > 0.8  # the camera is above the cylinders' tops
    for obj in (o for o in at.test_site.site_objects if o.row == "row1"):
        shown = shown_area(src, obj.name, bound=True)
        assert shown is not None
        expected = min(_facing_arc_m(cam_xz, obj), obj.height)
        # samples are cell centres: an arc of n steps holds n − 1 … n whole cells
        assert expected - 2.5 * SAMPLE_STEP_M <= shown.square_m <= expected + SAMPLE_STEP_M, \
            (obj.name, shown.square_m, expected)
        assert shown.top_fraction > 0.97, (obj.name, shown.top_fraction)


def _independent_square(view, isp: IspView) -> float:
    """The largest shown square (m), with the RVM border tested point by point through the
    exact map (not the footprint polygon) and the square found by brute force over every
    position and size (not by erosion)."""
    px = view.side_px.reshape(-1, 2).astype(np.float64)
    uv, ok = input_to_output(isp.params, px, isp.input_size, isp.output)
    w, h = isp.output.width, isp.output.height
    inside = (ok & (uv[:, 0] >= -0.5) & (uv[:, 0] <= w - 0.5) & (uv[:, 1] >= -0.5)
              & (uv[:, 1] <= h - 0.5)).reshape(view.side_seen.shape)
    shown = view.side_seen & inside
    rows, cols = shown.shape
    wrapped = np.concatenate([shown, shown], axis=1).astype(np.int32)
    integral = np.pad(wrapped.cumsum(0).cumsum(1), ((1, 0), (1, 0)))
    best = 0
    for k in range(1, rows + 1):
        sums = (integral[k:, k:] - integral[:-k, k:] - integral[k:, :-k] + integral[:-k, :-k])
        if not (sums[:, :cols] == k * k).any():
            break
        best = k
    return best * view.step_m


def test_an_rvm_border_across_row_1_shrinks_the_square_as_the_exact_map_says(low_body):
    """Settings whose RVM image cuts row 1 at different heights: the measured square agrees
    with the brute-force square over the exactly mapped samples (within a step and a pixel
    at the border), and R158-1 passes exactly when a 0.15 m square or the whole top shows."""
    at, images, ctx = low_body
    crit = load_criteria("unr158")
    size = (images.camera.width, images.camera.height)
    checked, passes, fails = 0, 0, 0
    for v_shift in np.linspace(-0.5, 0.5, 9):
        params = IspParams(fov=180.0, rad=160.0, zoom=0.9, adv_v_shift=float(v_shift))
        isp = IspView(params, size, OUT)
        src = LabelSource(np.zeros((1, 1), np.uint8), context=ctx, isp=isp)
        margins = []
        for obj in (o for o in at.test_site.site_objects if o.row == "row1"):
            view = surface_view(ctx, obj.name)
            shown = shown_area(src, obj.name)
            assert view is not None and shown is not None
            assert abs(shown.square_m - _independent_square(view, isp)) <= 2 * SAMPLE_STEP_M
            margins.append(max(shown.square_m / 0.15, shown.top_fraction))
            checked += 1
        ec = evaluate_params(images, params, OUT, crit, annotate=False).ec["R158-1"]
        assert ec.value == pytest.approx(min(margins), abs=0.07)
        assert ec.passed == (min(margins) >= 1.0) or abs(min(margins) - 1.0) < 0.07
        passes += ec.passed
        fails += not ec.passed
    assert checked == 27 and passes and fails  # the sweep crosses the limit both ways


def test_a_square_without_the_top_passes_and_a_sliver_fails(low_body):
    """Somewhere in a sweep of the view's height a row-1 cylinder shows ≥ 0.15 m of side
    with its top partly cut (passes through the area rule alone), and elsewhere less than
    0.15 m with no whole top (fails)."""
    at, images, ctx = low_body
    size = (images.camera.width, images.camera.height)
    obj = next(o for o in at.test_site.site_objects if o.name == "row1.2")
    square_only, sliver = False, False
    for v_shift in np.linspace(-0.6, 0.6, 25):
        for zoom in (0.9, 1.4, 2.0):
            params = IspParams(fov=180.0, rad=160.0, zoom=zoom, adv_v_shift=float(v_shift))
            src = LabelSource(np.zeros((1, 1), np.uint8), context=ctx,
                              isp=IspView(params, size, OUT))
            shown = shown_area(src, obj.name)
            assert shown is not None
            if shown.square_m >= 0.15 and shown.top_fraction < 0.9:
                square_only = True
                assert shown.margin(0.15) >= 1.0
            if 0 < shown.square_m < 0.15 and shown.top_fraction < 0.9:
                sliver = True
                assert shown.margin(0.15) < 1.0
    assert square_only and sliver
