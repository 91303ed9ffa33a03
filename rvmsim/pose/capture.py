"""Captures of the physical camera: reading them, checking them, their grey levels."""

from __future__ import annotations

import re
import struct
import warnings
import zlib
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np
from PIL import Image, UnidentifiedImageError

from .._io import max_image_pixels
from ..camera import FisheyeCamera
from ..errors import InputFileError, RvmsimError


__all__ = ["load_capture", "check_captures", "check_capture_size", "grey", "capture_header_size",
           "CAPTURE_SUFFIXES", "capture_files", "capture_folders"]


def load_capture(path: str | Path, camera: FisheyeCamera | None = None) -> np.ndarray:
    """Read a capture as (H, W, 3) uint8 RGB.

    Grey images are expanded to three channels, an alpha channel is dropped, 16-bit images
    are scaled to 8 bits (the high byte).

    Parameters
    ----------
    path : path
        PNG, JPEG, TIFF, BMP or any other format PIL reads.
    camera : FisheyeCamera, optional
        When given, the capture must be ``camera.width`` × ``camera.height`` px.

    Raises
    ------
    RvmsimError
        One line naming the file: missing, unreadable, empty or blank, over the image pixel
        limit (``RVMSIM_MAX_IMAGE_PIXELS``), or (with ``camera``) a size other than the
        camera's; the size is checked from the file's header, before the pixels are decoded.
    """
    path = Path(path)
    w, h = capture_header_size(path)
    if camera is not None and (w, h) != (camera.width, camera.height):
        raise _size_error(path, w, h, camera)
    limit = max_image_pixels()
    if w * h > limit:
        raise InputFileError(str(path), "", f"capture is {w}×{h} = {w * h} px, over the limit "
                             f"of {limit} px (raise it with RVMSIM_MAX_IMAGE_PIXELS)")
    img = _decode(path)
    h, w = img.shape[:2]
    if camera is not None and (w, h) != (camera.width, camera.height):
        raise _size_error(path, w, h, camera)
    if float(img.std()) < 1.0:
        raise RvmsimError(f"{path}: capture is blank (every pixel ≈ {int(img.mean())})")
    return img


def check_captures(paths: Sequence[str | Path], camera: FisheyeCamera | None = None
                   ) -> list[tuple[int, int]]:
    """Read every capture once (:func:`load_capture`, decoded and dropped one at a time), so
    that a command given several refuses a missing, unreadable, corrupt, empty or blank one
    (a folder or a zero-byte file too) before any work, rather than after validating or
    detecting in the others.

    Returns
    -------
    list of (int, int)
        Each capture's (width, height), px.

    Raises
    ------
    RvmsimError
        One line naming the first capture at fault (:func:`load_capture`).
    """
    sizes = []
    for path in paths:
        img = load_capture(path, camera)
        sizes.append((int(img.shape[1]), int(img.shape[0])))
    return sizes


def _size_error(path: Path, w: int, h: int, camera: FisheyeCamera) -> InputFileError:
    return InputFileError(str(path), "", f"capture is {w}×{h} px but the scene's "
                          f"camera.image_size is {camera.width}×{camera.height} px")


def capture_header_size(path: Path) -> tuple[int, int]:
    """(width, height) in px of the image file at ``path``, from its header alone (PIL's
    lazy open: no pixel is decoded).

    Raises
    ------
    InputFileError
        One line naming the file: missing, empty, unreadable or not an image, or a header
        so large that PIL refuses it as a decompression bomb.
    """

    if not path.exists():
        raise InputFileError(str(path), "", "capture not found")
    if not path.is_file():
        raise InputFileError(str(path), "", "capture is not a file")
    try:
        if path.stat().st_size == 0:
            raise InputFileError(str(path), "", "capture is an empty file")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # our own limit
            with Image.open(path) as im:
                return int(im.width), int(im.height)
    except Image.DecompressionBombError as err:  # "Image size (N pixels) exceeds limit …"
        pixels = re.search(r"\((\d+) pixels\)", str(err))
        said = f"{pixels.group(1)} px" if pixels else "more pixels than PIL opens"
        raise InputFileError(str(path), "", f"capture's header says {said}, over the limit of "
                             f"{max_image_pixels()} px") from None
    except UnidentifiedImageError:
        raise InputFileError(str(path), "", "cannot read capture (not a PNG, JPEG, TIFF or "
                             "other image file)") from None
    except OSError as err:
        raise InputFileError(str(path), "", f"cannot read capture ({err.strerror or err})"
                             ) from None


def _decode(path: Path) -> np.ndarray:
    """The file's pixels as 8-bit RGB (PIL decodes them: unlike OpenCV's, its decoders
    report a truncated or corrupt file as an exception, not as lines on stderr)."""

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)  # checked already
            with Image.open(path) as im:
                im.load()
                return _to_rgb8(im, path)
    except (OSError, SyntaxError, ValueError, EOFError, struct.error, zlib.error) as err:
        # PIL says "broken PNG file" with a SyntaxError, "image file is truncated" with OSError
        first = (str(err).strip().splitlines() or [type(err).__name__])[0][:160]
        raise InputFileError(str(path), "", f"cannot read capture ({first})") from None


def _to_rgb8(im: Image.Image, path: Path) -> np.ndarray:
    """(H, W, 3) uint8 RGB from a loaded PIL image: 16-bit grey scaled to 8 bits (its high
    byte, as PIL keeps of 16-bit colour), grey expanded to three channels, alpha dropped."""
    if im.mode in ("I;16", "I;16B", "I;16L", "I"):
        arr = np.asarray(im)
        if arr.min(initial=0) < 0 or arr.max(initial=0) > 65535:
            raise InputFileError(str(path), "", "capture has 32-bit pixels (need 8- or 16-bit)")
        grey8 = (arr.astype(np.uint16) >> 8).astype(np.uint8)
        return np.repeat(grey8[:, :, None], 3, axis=2)
    if im.mode == "F":
        raise InputFileError(str(path), "", "capture has float32 pixels (need 8- or 16-bit)")
    if im.mode in ("L", "LA", "1"):
        grey8 = np.asarray(im.convert("L"), dtype=np.uint8)
        return np.repeat(grey8[:, :, None], 3, axis=2)
    return np.ascontiguousarray(np.asarray(im.convert("RGB"), dtype=np.uint8))


def check_capture_size(capture: np.ndarray, camera: FisheyeCamera, capture_name: str) -> None:
    """Refuse a capture that is not an (H, W, 3) image of ``camera``'s size.

    Raises
    ------
    RvmsimError
        One line naming ``capture_name`` and both sizes (px).
    """
    if capture.shape[:2] != (camera.height, camera.width) or capture.ndim != 3:
        raise RvmsimError(f"{capture_name}: capture is {capture.shape[1]}×{capture.shape[0]} px "
                          f"but the scene's camera is {camera.width}×{camera.height} px")


def grey(rgb: np.ndarray) -> np.ndarray:
    """Grey levels (0..255, float32, (H, W)) of an (H, W, 3) uint8 RGB image."""

    return np.asarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY), dtype=np.float32)


#: File endings of the captures a folder given to ``--capture`` holds.
CAPTURE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff")


def capture_files(paths: Sequence[Path]) -> list[Path]:
    """The capture files: each path given, or the images (:data:`CAPTURE_SUFFIXES`, sorted
    by name) in each folder given.

    Raises
    ------
    RvmsimError
        A folder without any capture, or with a link named as a capture to a file that is
        not there (a car would be left out silently).
    """
    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            named = sorted(f for f in p.iterdir() if f.suffix.lower() in CAPTURE_SUFFIXES)
            for f in named:
                if f.is_symlink() and not f.exists():  # a car whose capture is gone
                    raise RvmsimError(f"{f}: a link to a missing file (--capture {p})")
            found = [f for f in named if f.is_file()]  # a folder named like one is not
            if not found:
                raise RvmsimError(f"{p}: no captures ({', '.join(CAPTURE_SUFFIXES)}) in this "
                                  "folder (--capture)")
            out += found
        else:
            out.append(p)
    return out


def capture_folders(captures: Sequence[Path], out_dir: Path) -> list[Path]:
    """One output folder per capture: ``out_dir/<capture name>``, a name met again numbered
    (``front``, ``front_2``, …)."""
    used: set[str] = set()
    out: list[Path] = []
    for cap in captures:
        name, n = cap.stem, 2
        while name in used:
            name, n = f"{cap.stem}_{n}", n + 1
        used.add(name)
        out.append(out_dir / name)
    return out
