"""rvmsim.pose.capture: reading captures and checking their size."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.pose import load_capture
from rvmsim.pose.capture import check_capture_size

from rvmsim.testing.captures import base


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


def _png_header(width: int, height: int) -> bytes:
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", b"") + chunk(b"IEND", b"")


@pytest.mark.parametrize("size, words", [
    ((100000, 100000), "header says 10000000000 px"),
    ((8000, 7000), "56000000 px, over the limit"),
])
def test_a_huge_header_is_refused_before_decoding(tmp_path, size, words):
    import resource

    path = tmp_path / "big.png"
    path.write_bytes(_png_header(*size))
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(RvmsimError, match=words):
        load_capture(path)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000  # KiB


def test_the_header_size_is_checked_against_the_camera_before_decoding(tmp_path):
    _, syn = base()
    path = tmp_path / "wrong.png"
    path.write_bytes(_png_header(4000, 3000))  # no pixel data: decoding would fail
    with pytest.raises(RvmsimError, match="4000×3000 px but the scene's camera.image_size"):
        load_capture(path, syn.camera)


def test_a_truncated_capture_is_one_line(tmp_path):
    path = tmp_path / "t.png"
    cv2.imwrite(str(path), np.random.default_rng(0).integers(0, 255, (48, 64, 3), np.uint8))
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(RvmsimError, match="cannot read capture") as err:
        load_capture(path)
    assert "\n" not in str(err.value)
