"""Captures for ``rvmsim calibrate``: image files (or folders of them) read as grey."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .board import CalibrationInputError

__all__ = ["capture_files", "load_grey"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


def capture_files(paths: list[str | Path]) -> list[Path]:
    """The image files among ``paths``, a folder standing for its images (sorted).

    Raises
    ------
    CalibrationInputError
        A path that does not exist, or a folder without images.
    """
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.suffix.lower() in IMAGE_SUFFIXES)
            if not found:
                raise CalibrationInputError(str(p), "", "folder has no images "
                                            f"({', '.join(IMAGE_SUFFIXES)})")
            out += found
        elif p.is_file():
            out.append(p)
        else:
            raise CalibrationInputError(str(p), "", "capture not found")
    return out


def load_grey(path: str | Path) -> np.ndarray:
    """The capture as (H, W) uint8 grey (8/16-bit, grey/RGB/RGBA).

    Raises
    ------
    CalibrationInputError
        When the file is not a readable image.
    """
    import cv2

    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None or img.size == 0:
        raise CalibrationInputError(str(path), "", "not a readable image (PNG/JPEG/TIFF/BMP)")
    if img.dtype != np.uint8:
        img = cv2.normalize(img.astype(np.float64), None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY)
    return img
