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
