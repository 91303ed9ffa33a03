"""Writing images with one-line errors (PNG through imageio)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import RvmsimError

__all__ = ["write_png"]


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
