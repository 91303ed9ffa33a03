"""Hard board captures (rvmsim/testing/hard_captures.py) and `validate` from hard starts on
them (issue 28): the board close and cut by the image border, at the fisheye rim, partly
beyond the lens's field, and close boards of each symmetry kind.

From a start ±10° / ±0.3 m off, a validation either converges (the board's corners
reprojected with the recovered pose within 0.5 px of the truth's, the pose within 5 mm and
0.1°) or refuses with ``ValidationFailure``: it never reports a wrong pose.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.scene import checker_corners
from rvmsim.validate import Validation, ValidationFailure, ValidationSettings, validate

from rvmsim.testing.hard_captures import (CASES, board_inner_corners, corner_view, hard_capture,
                                          hard_scene, hard_truth, whole_board_detected)

#: Two starts at the corners of the ±0.3 m / ±10° box: (Δposition m, Δyaw/pitch/roll °).
HARD_STARTS = {
    "high-fwd": ((0.3, -0.3, -0.3), (10.0, -10.0, 10.0)),
    "low-back": ((-0.3, 0.3, 0.3), (-10.0, 10.0, -10.0)),
    # tools/bench_starts.py's starts 9, 4 and 3 (seed 0), rounded.  Before issue 28, from
    # bench-9 the fisheye-edge board's corners fit a pose two squares along the board off
    # (160 mm, RMS 0.06 px), from bench-4 the board cut on two sides likewise (141 mm); from
    # bench-3 the board cut on one side gave perspective-view corners outside the capture
    # and cv2.cornerSubPix raised.
    "bench-9": ((0.057, -0.097, -0.065), (7.8, -5.5, 2.5)),
    "bench-4": ((0.214, -0.28, 0.138), (-6.5, 7.3, 0.8)),
    "bench-3": ((0.064, 0.138, 0.026), (8.7, 6.3, -10.0)),
}
#: Converged: pose within these of the truth (mm each axis, degrees each angle), and the
#: board's corners reprojected within this of the truth's (px).
POSITION_MM, ANGLE_DEG, PIXEL_PX = 5.0, 0.1, 0.5
#: Seen nearly edge-on at the fisheye's rim, the odd × even board's 10 corners in view pin the
#: angles only to ±0.15-0.36° (one standard error): it converges within the pose's own
#: uncertainty, not within 0.1°.
EDGE_ON = pytest.mark.xfail(strict=False, reason="10 corners edge-on pin the angles to ~0.3°")
#: One start per case: the starts where main reported a wrong pose or crashed before issue 28
#: for the cut and rim cases, a box corner for the others (7 validations;
#: tools/bench_starts.py runs many more).
STARTS = [("outside_fov", "low-back"), ("alias_7x9", "low-back"),
          ("odd_even_7x10", "high-fwd"), ("even_even_8x6", "low-back"),
          ("fisheye_edge", "bench-9"), ("cut_two_sides", "bench-4"), ("cut_one_side", "bench-3")]
#: The starts of the fast tier (the others are in the slow one: ``-m slow``).
FAST_STARTS = (("alias_7x9", "low-back"), ("cut_two_sides", "bench-4"))


def _tier(name: str, start: str) -> tuple[pytest.MarkDecorator, ...]:
    return () if (name, start) in FAST_STARTS else (pytest.mark.slow,)


def _usable(name: str) -> np.ndarray:
    """The true corners a sub-pixel check can use: in view, the board's label all around
    (not occluded, not at the plate's or image's edge), neighbours ≥ 8 px away."""
    view, truth = corner_view(name), hard_truth(name)
    nx, ny = CASES[name].board["squares"]
    grid = view.uv.reshape(nx - 1, ny - 1, 2)
    gap = np.full(grid.shape[:2], np.inf)
    for axis in (0, 1):
        d = np.linalg.norm(np.diff(grid, axis=axis), axis=-1)
        pad = [(0, 0), (0, 0)]
        pad[axis] = (1, 0)
        gap = np.minimum(gap, np.pad(d, pad, constant_values=np.inf))
        pad[axis] = (0, 1)
        gap = np.minimum(gap, np.pad(d, pad, constant_values=np.inf))
    h, w = truth.labels.shape
    ok = view.in_view & (gap.ravel() >= 8.0)
    for n in np.flatnonzero(ok):
        x, y = np.round(view.uv[n]).astype(int)
        win = truth.labels[max(y - 4, 0):y + 5, max(x - 4, 0):x + 5]
        ok[n] = 4 <= x < w - 4 and 4 <= y < h - 4 and bool(np.all(win == L.BOARD))
    return ok


@pytest.mark.parametrize("name", CASES)
def test_hard_capture_shows_the_board_where_the_projection_puts_it(name):
    """The board's corners from its fields alone are rvmsim's checker corners; rvmsim's
    projection agrees with cv2.fisheye's; and the rendered capture has its corners there
    (cv2.cornerSubPix on the clean render moves them ≤ 0.3 px, median ≤ 0.12 px)."""
    scene, truth, view = hard_scene(name), hard_truth(name), corner_view(name)
    ours = np.array([c.point for c in checker_corners(scene)])
    np.testing.assert_allclose(ours, board_inner_corners(CASES[name].board).reshape(-1, 3),
                               atol=1e-9)
    uv, _ = truth.camera.project(ours)
    np.testing.assert_allclose(uv[view.in_view], view.uv[view.in_view], atol=1e-6)
    ok = _usable(name)
    assert ok.sum() >= 8, ok.sum()
    grey = cv2.cvtColor(truth.color, cv2.COLOR_RGB2GRAY).astype(np.float32)
    found = cv2.cornerSubPix(grey, view.uv[ok].astype(np.float32).reshape(-1, 1, 2).copy(),
                             (3, 3), (-1, -1),
                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
    shift = np.linalg.norm(found.reshape(-1, 2) - view.uv[ok], axis=1)
    assert shift.max() <= 0.3 and np.median(shift) <= 0.12, (shift.max(), np.median(shift))


def test_hard_cases_are_hard_the_way_they_say():
    """Cut by the image border, beyond the lens's field, at the rim, hidden by the body."""
    v = {name: corner_view(name) for name in CASES}
    size = {name: CASES[name].camera["image_size"] for name in CASES}

    def out_of_image(name: str) -> tuple[np.ndarray, ...]:
        """Corners inside the lens's field but outside the image; past the right, top and
        left borders."""
        u, w = v[name].uv, size[name]
        inside_fov = v[name].off_axis_deg <= CASES[name].camera["lens"]["fov_deg"] / 2
        return (inside_fov & ~v[name].in_view, u[:, 0] > w[0] - 0.5, u[:, 1] < -0.5,
                u[:, 0] < -0.5)

    cut, right, top, left = out_of_image("cut_one_side")
    assert cut.any() and np.all(right[cut])  # a column cut by the right border only
    cut, _, top, left = out_of_image("cut_two_sides")
    assert np.any(cut & top) and np.any(cut & left)
    edge = v["fisheye_edge"]
    assert edge.in_view.all() and edge.off_axis_deg.max() >= 90.0
    fov = v["outside_fov"]
    assert CASES["outside_fov"].camera["lens"]["fov_deg"] == 180
    assert np.sum(fov.off_axis_deg > 90.0) >= 5 and np.sum(fov.in_view) >= 30
    cut, _, top, _ = out_of_image("odd_even_7x10")
    assert np.sum(cut & top) >= 6
    assert v["alias_7x9"].in_view.all()
    hidden = v["even_even_8x6"].in_view & ~_usable("even_even_8x6")
    assert hidden.sum() >= 2
    for name, squares in (("alias_7x9", [7, 9]), ("odd_even_7x10", [7, 10]),
                          ("even_even_8x6", [8, 6])):
        assert CASES[name].board["squares"] == squares


@pytest.mark.parametrize("name", CASES)
def test_whole_board_detector_on_hard_captures(name):
    """``cv2.findChessboardCornersSB`` misses the whole board in every hard case but the
    whole close 7 × 9 one; where it finds it, its corners are the true ones (≤ 1 px)."""
    found = whole_board_detected(hard_capture(name), tuple(CASES[name].board["squares"]))
    assert (found is not None) == CASES[name].whole_board_found
    if found is not None:
        true = corner_view(name).uv
        nearest = np.linalg.norm(found[:, None] - true[None], axis=-1).min(axis=1)
        assert nearest.max() <= 1.0, nearest.max()


@functools.lru_cache(maxsize=None)
def _outcome(name: str, start: str) -> Validation | ValidationFailure:
    """``validate`` of case ``name``'s capture from start ``start``: its result, or the
    failure it raised."""
    d_pos, d_ypr = HARD_STARTS[start]
    try:
        return validate(hard_scene(name, d_pos, d_ypr), hard_capture(name),
                        ValidationSettings(rerender=False))
    except ValidationFailure as fail:
        return fail


def _convergence_errors(name: str, res: Validation) -> tuple[float, float, float]:
    """(largest corner reprojection error px, position error mm, angle error °) of the
    recovered pose against the truth; the corners are those the truth sees."""
    c, truth = res.correction, CASES[name].mount
    got = {"position": list(c.position_m), "yaw_deg": c.yaw_deg, "pitch_deg": c.pitch_deg,
           "roll_deg": c.roll_deg}
    want = corner_view(name)
    seen = corner_view(name, got)
    px = float(np.linalg.norm(seen.uv - want.uv, axis=1)[want.in_view].max())
    mm = float(np.abs(np.subtract(c.position_m, truth["position"])).max() * 1000)
    deg = float(max(abs(c.yaw_deg - truth["yaw_deg"]), abs(c.pitch_deg - truth["pitch_deg"]),
                    abs(c.roll_deg - truth["roll_deg"])))
    return px, mm, deg


@pytest.mark.parametrize("name, start", [pytest.param(name, start, marks=_tier(name, start))
                                         for name, start in STARTS])
def test_hard_start_never_reports_a_wrong_pose(name, start):
    """Converged, or refused with a failure naming its step: never a wrong pose."""
    out = _outcome(name, start)
    if isinstance(out, ValidationFailure):
        assert out.step in ("detection", "correspondence", "pose fit"), out.step
        assert f"(step failed: {out.step})" in str(out)
        return
    px, mm, deg = _convergence_errors(name, out)
    # off by more than the tolerance and than three of its own standard errors: a pose the
    # data do not support (a few corners seen edge-on pin the angles only to ~0.3°)
    sigma_mm = 3.0 * max(out.correction.sigma_position_mm)
    sigma_deg = 3.0 * max(out.correction.sigma_angles_deg)
    assert px <= PIXEL_PX and mm <= max(POSITION_MM, sigma_mm) \
        and deg <= max(ANGLE_DEG, sigma_deg), (
        f"wrong pose reported: corners {px:.2f} px, {mm:.1f} mm, {deg:.3f}° off "
        f"(3σ: {sigma_mm:.1f} mm, {sigma_deg:.2f}°; start: {out.start})")


def _converges_marks(name: str, start: str) -> tuple[pytest.MarkDecorator, ...]:
    return ((EDGE_ON,) if name == "odd_even_7x10" else ()) + _tier(name, start)


@pytest.mark.parametrize("name, start", [pytest.param(name, start, marks=_converges_marks(name, start))
                                         for name, start in STARTS])
def test_hard_start_converges(name, start):
    """Every hard case converges from a ±10° / ±0.3 m start: the partial-board start finds
    the board cut by the image, beyond the lens's field and at its rim, and the squares'
    colours where readings differ refute the two-square aliases (the edge-on board within
    its own uncertainty only: xfail)."""
    out = _outcome(name, start)
    assert isinstance(out, Validation), f"refused: {out}"
    px, mm, deg = _convergence_errors(name, out)
    assert px <= PIXEL_PX, px
    assert mm <= POSITION_MM, mm
    assert deg <= ANGLE_DEG, deg
