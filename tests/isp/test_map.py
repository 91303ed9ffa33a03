"""The fast ISP map: its error bound against the exact map, straight lines, the effect of each
parameter on real renders (Table 3), mirroring, the ray cache."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.isp import (
    PARAM_SPECS,
    IspParams,
    OutputSpec,
    RayCache,
    apply_map,
    build_map,
    build_map_exact,
    map_nodes,
)

from ..conftest import sensor_render, small_render
from .conftest import INPUT


def test_fast_map_error_bound_over_random_parameter_sets():
    """The interpolated map stays within 0.1 px of the exact map wherever it reads the
    input image, for random parameter sets over every range of Table 2."""
    rng = np.random.default_rng(42)
    out = OutputSpec(640, 480)
    worst = 0.0
    for i in range(40):
        kw = {s.name: rng.uniform(s.low, s.high) for s in PARAM_SPECS}
        if i % 2:  # half of them as the paper tunes: angles at 0
            kw.update(h_pan=0, v_pan=0, tilt=0, theta=0, phi=0)
        p = IspParams(**kw)
        fast, exact = build_map(p, INPUT, out), build_map_exact(p, INPUT, out)
        inside = ((exact.map_x >= -1) & (exact.map_x <= INPUT[0]) & (exact.map_y >= -1)
                  & (exact.map_y <= INPUT[1]))
        if inside.any():
            err = np.hypot(fast.map_x - exact.map_x, fast.map_y - exact.map_y)[inside]
            worst = max(worst, float(err.max()))
    assert worst <= 0.1


# ---------------------------------------------------------------------------- real images
# ---------------------------------------------------------------------------- real images
def _pinhole_params(cam) -> IspParams:
    """FOV/RAD matching the (equidistance) lens, all angles 0: a pinhole V camera."""
    return IspParams(fov=180.0, rad=cam.fx * math.pi / 2,
                     h_shift=cam.cx - (cam.width - 1) / 2, v_shift=cam.cy - (cam.height - 1) / 2)


def _line_fit_residuals(labels: np.ndarray, color: np.ndarray, label: int) -> np.ndarray:
    """Residuals (px) of a line fitted to the per-row centroids of a yellow guideline.

    The centroid of each row is weighted by "yellowness" of the bilinear colour image near
    the line's label (sub-pixel, unlike the staircase of nearest-sampled labels); rows where
    the line meets a cross line, the bumper or the image border are left out."""
    near = cv2.dilate((labels == label).astype(np.uint8), np.ones((5, 5), np.uint8)) > 0
    other = (labels >= L.guide_cross(1)) & (labels <= L.guide_cross(L.MAX_CROSS_LINES))
    other |= (labels == L.BUMPER) | (labels == L.VOID)
    other = cv2.dilate(other.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0
    c = color.astype(float)
    weight = np.clip((c[..., 0] + c[..., 1]) / 2 - c[..., 2] - 40, 0, None) * near
    rows = np.nonzero((weight.sum(axis=1) > 0) & ~(near & other).any(axis=1))[0]
    cols = (weight[rows] * np.arange(labels.shape[1])).sum(axis=1) / weight[rows].sum(axis=1)
    return cols - np.polyval(np.polyfit(rows, cols, 1), rows)


def test_straight_edges_stay_straight_with_matching_lens():
    img = sensor_render("a")  # equidistance lens, 1280 × 960: straight to a fraction of a px
    cam = img.camera
    out = OutputSpec(640, 360, mirror=False)

    def residuals(params, label):
        m = build_map(params, (cam.width, cam.height), out)
        return _line_fit_residuals(apply_map(img.labels, m), apply_map(img.color, m), label)

    for label in (L.GUIDE_SIDE_NEG_X, L.GUIDE_SIDE_POS_X):
        res = residuals(_pinhole_params(cam), label)
        assert len(res) > 100
        assert np.sqrt(np.mean(res**2)) <= 0.5 and np.abs(res).max() <= 0.75, label
    # The test can fail: a lens model 25 % off bends the same lines.
    bent = _pinhole_params(cam).replace(rad=_pinhole_params(cam).rad * 1.25)
    assert np.sqrt(np.mean(residuals(bent, L.GUIDE_SIDE_NEG_X) ** 2)) > 1.0


def _stats(labels, label):
    rows, cols = np.nonzero(labels == label)
    assert rows.size > 30, f"label {label} barely visible"
    return dict(cx=cols.mean(), cy=rows.mean(), area=rows.size,
                w=cols.max() - cols.min() + 1, h=rows.max() - rows.min() + 1)


@pytest.fixture(scope="module")
def base():
    img = small_render("a")
    cam = img.camera
    params = _pinhole_params(cam).replace(zoom=0.8)
    out = OutputSpec(640, 360, mirror=False)

    def run(**changes):
        m = build_map(params.replace(**changes), (cam.width, cam.height), out)
        return apply_map(img.labels, m)

    return run


def test_h_and_v_shift_move_the_roi(base):
    ref, right, down = base(), base(h_shift=40.0), base(v_shift=40.0)
    b0, b1, b2 = (_stats(x, L.BOARD) for x in (ref, right, down))
    assert b1["cx"] < b0["cx"] - 20 and abs(b1["cy"] - b0["cy"]) < 8   # ROI right → content left
    assert b2["cy"] < b0["cy"] - 20 and abs(b2["cx"] - b0["cx"]) < 8   # ROI down → content up


def test_zoom_enlarges(base):
    a0, a1 = _stats(base(), L.BOARD)["area"], _stats(base(zoom=1.2), L.BOARD)["area"]
    assert a1 / a0 == pytest.approx((1.2 / 0.8) ** 2, rel=0.15)


def test_advanced_scale_stretches_one_axis(base):
    b0 = _stats(base(), L.BOARD)
    bh = _stats(base(adv_h_scale=1.5), L.BOARD)
    bv = _stats(base(adv_v_scale=1.5), L.BOARD)
    assert bh["w"] / b0["w"] == pytest.approx(1.5, rel=0.06)
    assert bh["h"] / b0["h"] == pytest.approx(1.0, abs=0.06)
    assert bv["h"] / b0["h"] == pytest.approx(1.5, rel=0.06)
    assert bv["w"] / b0["w"] == pytest.approx(1.0, abs=0.06)


def test_advanced_shift_moves_by_half_widths(base):
    b0 = _stats(base(), L.BOARD)
    bx = _stats(base(adv_h_shift=0.2), L.BOARD)
    by = _stats(base(adv_v_shift=-0.15), L.BOARD)
    assert bx["cx"] - b0["cx"] == pytest.approx(-0.2 * 320, abs=1.5)
    assert by["cy"] - b0["cy"] == pytest.approx(0.15 * 320, abs=1.5)


def test_pan_turns_the_view(base):
    b0 = _stats(base(), L.BOARD)
    right = _stats(base(h_pan=10.0, v_pan=0.0), L.BOARD)     # axis turned toward image right
    down = _stats(base(h_pan=10.0, v_pan=90.0), L.BOARD)     # … toward image bottom
    assert right["cx"] < b0["cx"] - 30 and abs(right["cy"] - b0["cy"]) < 15
    assert down["cy"] < b0["cy"] - 30 and abs(down["cx"] - b0["cx"]) < 15


def test_tilt_rolls_the_view(base):
    ref, rolled = base(), base(tilt=12.0)
    c = np.array([319.5, 179.5])
    angles = []
    for labels in (ref, rolled):
        s = _stats(labels, L.object_body("E"))
        angles.append(math.degrees(math.atan2(s["cy"] - c[1], s["cx"] - c[0])))
    assert angles[1] - angles[0] == pytest.approx(-12.0, abs=1.5)


def test_fov_and_rad_set_the_roi_size(base):
    a0 = _stats(base(), L.BOARD)["area"]
    assert _stats(base(rad=base_rad() * 1.2), L.BOARD)["area"] < 0.8 * a0
    assert _stats(base(fov=150.0), L.BOARD)["area"] < 0.8 * a0  # same RAD over fewer degrees


def base_rad() -> float:
    return _pinhole_params(small_render("a").camera).rad


def test_image_plane_tilt_gives_keystone(base):
    def ratio(labels):
        return _stats(labels, L.object_body("D"))["area"] / _stats(labels, L.object_body("E"))["area"]

    r0, r1, r2 = ratio(base()), ratio(base(theta=25.0, phi=0.0)), ratio(base(theta=25.0, phi=180.0))
    assert r1 > 1.15 * r0 and r2 < r0 / 1.15 or r1 < r0 / 1.15 and r2 > 1.15 * r0


def test_mirror_flips_horizontally_and_labels_stay_exact():
    img = small_render("b")
    cam = img.camera
    p = _pinhole_params(cam).replace(zoom=0.7, adv_v_shift=0.2)
    a = apply_map(img.labels, build_map(p, (cam.width, cam.height), OutputSpec(400, 300, True)))
    b = apply_map(img.labels, build_map(p, (cam.width, cam.height), OutputSpec(400, 300, False)))
    assert np.array_equal(a, b[:, ::-1])
    assert set(np.unique(a).tolist()) <= set(np.unique(img.labels).tolist()) | {L.VOID}
    # Bilinear colour remap of the same map, for comparison, blends values.
    col = apply_map(img.color, build_map(p, (cam.width, cam.height), OutputSpec(400, 300)))
    assert col.shape == (300, 400, 3)


def test_ray_cache_reuses_views_and_changes_no_node():
    """Candidates that differ only in FOV, RAD and the shifts share their ray planes: with a
    RayCache, map_nodes computes them once and gives bit-identical node grids."""
    out = OutputSpec(320, 240)
    cache = RayCache(size=4)
    rng = np.random.default_rng(5)
    views = [dict(zoom=z, adv_v_shift=s) for z, s in ((0.5, 0.2), (0.9, -0.1), (1.3, 0.0))]
    for view in views:
        for _ in range(4):
            p = IspParams(fov=rng.uniform(160, 200), rad=rng.uniform(500, 800),
                          h_shift=rng.uniform(-40, 40), v_shift=rng.uniform(-60, 60), **view)
            a, b = map_nodes(p, INPUT, out), map_nodes(p, INPUT, out, rays=cache)
            assert a.cell == b.cell and a.error_px == b.error_px
            assert np.array_equal(a.grid, b.grid)
    # the same view with other FOV/RAD/shifts is served from the cache, not recomputed
    p1 = IspParams(fov=170, rad=600, **views[0])
    p2 = IspParams(fov=190, rad=700, h_shift=12, v_shift=-30, **views[0])
    assert cache.planes(p1, out, 8) is cache.planes(p2, out, 8)
    assert cache.planes(p1, out, 8) is not cache.planes(IspParams(fov=170, rad=600, **views[1]), out, 8)
    assert len(cache._entries) <= 4  # never more than its size
