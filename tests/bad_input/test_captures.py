"""Bad captures for ``rvmsim validate --capture`` (issue #14, group 6): image headers far
larger than the camera (refused from the header, before any pixel is decoded: a
100000 × 100000 header gave a cv2.error, a 20000 × 20000 capture cost 1.6 GB), truncated or
corrupt files, files that are not images."""

from __future__ import annotations

import struct
import zlib

import pytest

from .conftest import SMALL_SCENE
from .harness import MEMORY, Case, check_case

VALIDATE = ("validate", SMALL_SCENE, "--out", "v", "--no-progress", "--capture")


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png(width: int, height: int, idat: bytes = b"") -> bytes:
    """A PNG of an 8-bit RGB ``width`` × ``height`` header, with ``idat`` as its pixel data."""
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", ihdr) + _chunk(b"IDAT", idat)
            + _chunk(b"IEND", b""))


def jpeg_header(width: int, height: int) -> bytes:
    """The start of a baseline JPEG whose frame header says ``width`` × ``height``."""
    sof = struct.pack(">BHHB", 8, height, width, 3) + b"\x01\x11\x00\x02\x11\x00\x03\x11\x00"
    return b"\xff\xd8" + b"\xff\xc0" + struct.pack(">H", len(sof) + 2) + sof + b"\xff\xd9"


def tiff_header(width: int, height: int) -> bytes:
    """A little-endian TIFF with one IFD saying ``width`` × ``height`` (no strips)."""
    entries = [(256, 4, 1, width), (257, 4, 1, height), (258, 3, 1, 8), (262, 3, 1, 1),
               (273, 4, 1, 0), (277, 3, 1, 1), (279, 4, 1, 0)]
    ifd = struct.pack("<H", len(entries)) + b"".join(
        struct.pack("<HHII", tag, kind, count, value) for tag, kind, count, value in entries)
    return b"II*\x00" + struct.pack("<I", 8) + ifd + b"\0\0\0\0"


def bmp_header(width: int, height: int) -> bytes:
    """A 24-bit BMP header saying ``width`` × ``height``, without pixels."""
    info = struct.pack("<IiiHHIIiiII", 40, width, height, 1, 24, 0, 0, 2835, 2835, 0, 0)
    return b"BM" + struct.pack("<IHHI", 14 + len(info), 0, 0, 14 + len(info)) + info


def _file(name: str, data: bytes | None):
    def setup(folder):
        if data is None:
            (folder / name).mkdir()
        else:
            (folder / name).write_bytes(data)
    return setup


#: (case id, file name, contents (None: a directory))
FILES = [
    ("png-100000", "cap.png", png(100000, 100000)),
    ("png-20000", "cap.png", png(20000, 20000)),
    ("png-8000", "cap.png", png(8000, 8000)),
    ("png-65535-wide", "cap.png", png(65535, 1)),
    ("png-right-size-no-data", "cap.png", png(320, 240)),
    ("png-right-size-corrupt", "cap.png", png(320, 240, zlib.compress(b"\x00" * 50) + b"xx")),
    ("png-truncated", "cap.png", png(320, 240, zlib.compress(b"\x01" * 5000))[:60]),
    ("jpeg-65000", "cap.jpg", jpeg_header(65000, 65000)),
    ("jpeg-4000", "cap.jpg", jpeg_header(4000, 3000)),
    ("jpeg-right-size-truncated", "cap.jpg", jpeg_header(320, 240)),
    ("tiff-100000", "cap.tif", tiff_header(100000, 100000)),
    ("bmp-100000", "cap.bmp", bmp_header(100000, 100000)),
    ("empty", "cap.png", b""),
    ("text", "cap.png", b"this is not an image\n" * 10),
    ("directory", "cap.png", None),
]
#: Cases run in a child of their own: headers of a gigabyte or more of pixels.
ISOLATED = {"png-100000": MEMORY, "png-20000": MEMORY, "jpeg-65000": MEMORY,
            "tiff-100000": MEMORY, "bmp-100000": MEMORY}
CASES = [Case(f"capture-{i}", VALIDATE + (name,), (name,), _file(name, data),
              isolate=ISOLATED.get(i, "")) for i, name, data in FILES]
CASES += [Case("capture-missing", VALIDATE + ("gone.png",), ("gone.png", "not found"))]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_capture(case, case_dir):
    check_case(case, case_dir)


def _folder_without_captures(folder):
    (folder / "caps").mkdir()
    (folder / "caps" / "notes.txt").write_text("no images here\n")


def _two_captures(folder):
    for name in ("a.png", "b.png"):
        (folder / name).write_bytes(b"")


def _folder_with_a_corrupt_capture(folder):
    (folder / "caps").mkdir()
    (folder / "caps" / "x.png").write_bytes(png(320, 240, zlib.compress(b"\x01" * 5000))[:60])


#: Several captures (issue #18): a folder without any, --write-scene with two, a folder
#: whose only capture is unreadable (its error is one stderr line; the summary is written).
CASES_SEVERAL = [
    Case("capture-folder-without-captures", VALIDATE + ("caps",), ("caps", "no captures"),
         _folder_without_captures),
    Case("write-scene-with-two-captures",
         ("validate", SMALL_SCENE, "--out", "v", "--no-progress", "--capture", "a.png",
          "--capture", "b.png", "--write-scene", "fixed.yaml"), ("--write-scene", "2 given"),
         _two_captures),
    Case("capture-folder-with-a-corrupt-capture", VALIDATE + ("caps",), ("x.png",),
         _folder_with_a_corrupt_capture),
]


@pytest.mark.parametrize("case", CASES_SEVERAL, ids=[c.id for c in CASES_SEVERAL])
def test_bad_captures_of_several(case, case_dir):
    check_case(case, case_dir)


def _noise_png(folder, name: str, size=(320, 240)) -> None:
    import imageio.v3 as iio
    import numpy as np

    noise = np.random.default_rng(7).integers(0, 255, (size[1], size[0], 3), dtype=np.uint8)
    iio.imwrite(folder / name, noise)


def _good_then(name: str, data: bytes | None):
    """Two good captures (of the camera's size), then ``name`` (None: a folder)."""
    def setup(folder):
        for good in ("good1.png", "good2.png"):
            _noise_png(folder, good)
        if data is None:
            (folder / name).mkdir()
        elif data != b"missing":
            (folder / name).write_bytes(data)
    return setup


#: Several captures, one of them bad after good ones (issue #30): refused before any work
#: (nothing rendered, searched or written), naming the bad one.
BAD_AMONG_GOOD = [
    ("missing", "gone.png", b"missing"),
    ("zero-bytes", "zero.png", b""),
    ("directory", "dir.png", None),
    ("corrupt", "bad.png", png(320, 240, zlib.compress(b"\x01" * 5000))[:60]),
    ("other-size", "small.png", png(32, 24)),
]
CASES_AMONG_GOOD = [
    Case(f"validate-{i}-among-good", ("validate", SMALL_SCENE, "--out", "v", "--no-progress",
                                      "--capture", "good1.png", "--capture", "good2.png",
                                      "--capture", name), (name,), _good_then(name, data)) for i, name, data in BAD_AMONG_GOOD]


@pytest.mark.parametrize("case", CASES_AMONG_GOOD, ids=[c.id for c in CASES_AMONG_GOOD])
def test_a_bad_capture_among_good_ones_is_refused_before_any_work(case, case_dir):
    out = check_case(case, case_dir)
    assert not (case_dir / "v").exists(), out.stdout
