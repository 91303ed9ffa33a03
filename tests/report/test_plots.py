"""The run report's plots: PNGs of the convergence curve and of the score distribution."""

from __future__ import annotations

import cv2
import numpy as np

from rvmsim.report import convergence_png, histogram_png


def _decode(png: bytes) -> np.ndarray:
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    assert img is not None
    return img


def test_convergence_and_histogram_are_pngs_with_content():
    curve = [(i, min(1.0, 1e-6 * 2 ** (i // 4)), "coarse" if i < 40 else "fine-1")
             for i in range(80)]
    for png in (convergence_png(curve), histogram_png(np.array([c[1] for c in curve])),
                histogram_png(np.zeros(5)), convergence_png([])):
        img = _decode(png)
        assert img.shape[0] > 100 and img.shape[1] > 100 and float(img.std()) > 5
