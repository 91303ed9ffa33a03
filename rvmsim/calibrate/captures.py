"""Captures for ``rvmsim calibrate``: image files (or folders of them) read as grey."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from ..pose import load_capture
from .board import CalibrationInputError

__all__ = ["board_images", "load_grey"]

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp")


def board_images(paths: list[str | Path]) -> list[Path]:
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
    """The capture as (H, W) uint8 grey, read by :func:`rvmsim.validate.load_capture`
    (8/16-bit, grey/RGB/RGBA; its header and pixel-limit checks).

    Raises
    ------
    RvmsimError
        One line naming the file: missing, unreadable, blank or over the pixel limit.
    """

    return cv2.cvtColor(load_capture(path), cv2.COLOR_RGB2GRAY)
