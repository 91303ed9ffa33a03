"""rvmsim.validate.capture: reading captures and checking their size."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.validate import load_capture
from rvmsim.validate.capture import check_capture_size

from .captures import base


def test_load_capture_formats(tmp_path):
    rng = np.random.default_rng(1)
    grey16 = rng.integers(0, 65535, (48, 64), dtype=np.uint16)
    cv2.imwrite(str(tmp_path / "g16.png"), grey16)
    img = load_capture(tmp_path / "g16.png")
    assert img.shape == (48, 64, 3) and img.dtype == np.uint8
    assert np.array_equal(img[..., 0], (grey16 >> 8).astype(np.uint8))
    bgra = rng.integers(0, 255, (48, 64, 4), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / "c.png"), bgra)
    img = load_capture(tmp_path / "c.png")
    assert np.array_equal(img, bgra[..., 2::-1])


def test_capture_size_is_checked_against_the_camera():
    _, syn = base()
    check_capture_size(syn.color, syn.camera, "cap.png")
    with pytest.raises(RvmsimError, match="cap.png: capture is 320×240 px but the scene's "
                                          "camera is 640×480"):
        check_capture_size(syn.color[::2, ::2], syn.camera, "cap.png")
    with pytest.raises(RvmsimError, match="cap.png"):
        check_capture_size(syn.color[..., 0], syn.camera, "cap.png")  # grey, not RGB
