"""The region of interest and the inverse map."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim.isp import OutputSpec, build_map_exact, draw_roi, input_to_output, roi_outline

from .conftest import INPUT, PARAM_SETS


def test_roi_outline_is_the_mapped_border_and_encloses_the_view():
    p = PARAM_SETS[1]
    out = OutputSpec(320, 180)
    poly = roi_outline(p, INPUT, out, samples_per_side=32)
    exact = build_map_exact(p, INPUT, out)
    assert np.allclose(poly[0], [exact.map_x[0, 0], exact.map_y[0, 0]], atol=1e-3)
    contour = poly.astype(np.float32).reshape(-1, 1, 2)
    for v, u in [(90, 160), (20, 30), (150, 300)]:
        assert cv2.pointPolygonTest(contour, (float(exact.map_x[v, u]),
                                              float(exact.map_y[v, u])), False) > 0
    img = np.zeros((INPUT[1], INPUT[0], 3), np.uint8)
    drawn = draw_roi(img, p, out)
    assert (drawn[..., 1] > 0).sum() > 500 and drawn[..., 0].max() == 0


@pytest.mark.parametrize("params", PARAM_SETS)
def test_input_to_output_inverts_the_map(params):
    out = OutputSpec(320, 180)
    exact = build_map_exact(params, INPUT, out)
    rng = np.random.default_rng(2)
    v, u = rng.integers(0, 180, 50), rng.integers(0, 320, 50)
    pts = np.stack([exact.map_x[v, u], exact.map_y[v, u]], 1)
    back, ok = input_to_output(params, pts, INPUT, out)
    assert ok.all()
    np.testing.assert_allclose(back, np.stack([u, v], 1), atol=1e-3)


@pytest.mark.parametrize("params", PARAM_SETS)
def test_input_to_plane_is_the_plane_point_each_output_pixel_shows(params):
    """Output pixels mapped into the fisheye image (exactly) come back from
    ``input_to_plane`` at the plane point step 2 of the model gives them, computed here from
    the output pixel alone: x_p = x_n / s_ox + x_os, y_p = y_n / s_oy + y_os."""
    from rvmsim.isp import input_to_plane
    from rvmsim.isp.exact import map_points

    out = OutputSpec(320, 180, mirror=True)
    u, v = np.meshgrid(np.linspace(0, 319, 23), np.linspace(0, 179, 13))
    u, v = u.ravel(), v.ravel()
    ui, vi, _ = map_points(params, u, v, INPUT, out)
    xy, ok = input_to_plane(params, np.stack([ui, vi], 1), INPUT)
    half = out.width / 2
    x_n = -(u - (out.width - 1) / 2) / half  # mirrored
    y_n = (v - (out.height - 1) / 2) / half
    expect = np.stack([x_n / params.adv_h_scale + params.adv_h_shift,
                       y_n / params.adv_v_scale + params.adv_v_shift], 1)
    assert ok.all()
    # every output pixel's plane point, to a millionth of a half-width (~1e-4 px)
    np.testing.assert_allclose(xy, expect, atol=1e-6)
