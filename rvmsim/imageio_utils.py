"""Reading and writing images with one-line errors (PNG through imageio)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import RvmsimError

__all__ = ["write_png", "read_image"]


def write_png(path: str | Path, image: np.ndarray) -> Path:
    """Write ``image`` ((H, W) or (H, W, 3) uint8) as PNG, creating the folder."""
    import imageio.v3 as iio

    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        iio.imwrite(path, np.ascontiguousarray(image), extension=".png")
    except OSError as err:
        raise RvmsimError(f"{path}: cannot write image ({err.strerror or err})") from None
    return path


def read_image(path: str | Path) -> np.ndarray:
    """Read an image file; raise :class:`RvmsimError` naming the file if it is unreadable."""
    import imageio.v3 as iio

    path = Path(path)
    if not path.is_file():
        raise RvmsimError(f"{path}: image file not found")
    try:
        img = iio.imread(path)
    except Exception as err:  # imageio raises plugin-specific errors
        raise RvmsimError(f"{path}: unreadable image ({type(err).__name__})") from None
    if img.size == 0:
        raise RvmsimError(f"{path}: empty image")
    return np.asarray(img)
