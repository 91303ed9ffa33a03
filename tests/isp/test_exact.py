"""The exact ISP map against an independent per-point evaluation of the documented formulas,
and the worked example of docs/isp-model.md."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rvmsim.isp import IspParams, OutputSpec, build_map, build_map_exact

from .conftest import INPUT, PARAM_SETS


def _reference_point(p: IspParams, u: float, v: float, inp, out: OutputSpec):
    """Independent per-point evaluation of the documented formulas, built from OpenCV's
    Rodrigues rotations and arccos instead of the module's matrices and atan2."""
    half = out.width / 2
    xn = (u - (out.width - 1) / 2) / half * (-1 if out.mirror else 1)
    yn = (v - (out.height - 1) / 2) / half
    xp, yp = xn / p.adv_h_scale + p.adv_h_shift, yn / p.adv_v_scale + p.adv_v_shift
    phi_st = math.radians(p.phi)
    axis = np.array([-math.sin(phi_st), math.cos(phi_st), 0.0]) * math.radians(p.theta)
    r_plane, _ = cv2.Rodrigues(axis)
    point = r_plane @ np.array([xp, yp, 0.0]) + np.array([0.0, 0.0, p.zoom])
    r_tilt, _ = cv2.Rodrigues(np.array([0.0, 0.0, math.radians(p.tilt)]))
    phi_cv = math.radians(p.v_pan)
    pan_axis = np.array([-math.sin(phi_cv), math.cos(phi_cv), 0.0]) * math.radians(p.h_pan)
    r_pan, _ = cv2.Rodrigues(pan_axis)
    ray = r_pan @ r_tilt @ point
    theta = math.acos(ray[2] / np.linalg.norm(ray))
    phi = math.atan2(ray[1], ray[0])
    f = p.rad / math.radians(p.fov / 2)
    return ((inp[0] - 1) / 2 + p.h_shift + f * theta * math.cos(phi),
            (inp[1] - 1) / 2 + p.v_shift + f * theta * math.sin(phi))


@pytest.mark.parametrize("params", PARAM_SETS)
@pytest.mark.parametrize("mirror", [True, False])
def test_map_matches_independent_per_point_formulas(params, mirror):
    out = OutputSpec(320, 180, mirror)
    fast = build_map(params, INPUT, out)
    exact = build_map_exact(params, INPUT, out)
    rng = np.random.default_rng(0)
    for u, v in zip(rng.integers(0, out.width, 60), rng.integers(0, out.height, 60)):
        ref = _reference_point(params, float(u), float(v), INPUT, out)
        assert np.hypot(exact.map_x[v, u] - ref[0], exact.map_y[v, u] - ref[1]) < 1e-3
        if 0 <= ref[0] < INPUT[0] and 0 <= ref[1] < INPUT[1]:
            assert np.hypot(fast.map_x[v, u] - ref[0], fast.map_y[v, u] - ref[1]) <= 0.1


def test_documented_worked_example():
    """docs/isp-model.md's hand-checkable example gives what the code gives."""
    p = IspParams(fov=190, rad=640, h_shift=10, v_shift=-20, zoom=0.8, adv_h_shift=0.1,
                  adv_v_shift=0.25, adv_h_scale=1.2, adv_v_scale=0.9)
    m = build_map_exact(p, (1280, 960), OutputSpec(1280, 720, True))
    assert m.map_x[500, 1000] == pytest.approx(497.66, abs=0.01)
    assert m.map_y[500, 1000] == pytest.approx(662.52, abs=0.01)


def test_rotations_are_proper_and_the_circle_flag_follows_fov():
    from rvmsim.isp.exact import map_points, plane_and_view

    for p in PARAM_SETS:
        for r in plane_and_view(p):
            np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
            assert np.linalg.det(r) == pytest.approx(1.0)
    out = OutputSpec(320, 180)
    u = np.array([159.5, 0.0])
    v = np.array([89.5, 0.0])
    # zoom 0.3: the corner's ray is ~73° off axis — inside a 180° circle, outside a 120° one
    _, _, wide = map_points(IspParams(fov=180, zoom=0.3), u, v, INPUT, out)
    _, _, narrow = map_points(IspParams(fov=120, zoom=0.3), u, v, INPUT, out)
    assert wide.tolist() == [True, True] and narrow.tolist() == [True, False]
