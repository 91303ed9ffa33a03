"""Checkerboard corners in a fisheye capture: OpenCV's sector-based detector, then the
classic detector with sub-pixel refinement, each on the capture and on a 2× upsampled copy
(small boards)."""

from __future__ import annotations

import numpy as np

from .board import BoardSpec

__all__ = ["find_board_corners"]


def _grey(image: np.ndarray) -> np.ndarray:
    import cv2

    if image.ndim == 3:
        image = cv2.cvtColor(np.ascontiguousarray(image[..., :3]), cv2.COLOR_RGB2GRAY)
    if image.dtype == np.uint8:
        return image
    lo, hi = float(image.min()), float(image.max())
    return ((image.astype(np.float64) - lo) * (255.0 / max(hi - lo, 1e-12))).astype(np.uint8)


def _classic(grey: np.ndarray, inner: tuple[int, int]) -> np.ndarray | None:
    """cv2.findChessboardCorners + cornerSubPix, (N, 2) float64 or None."""
    import cv2

    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, c = cv2.findChessboardCorners(grey, inner, flags=flags)
    if not ok:
        return None
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-3)
    c = cv2.cornerSubPix(grey, c.astype(np.float32), (5, 5), (-1, -1), crit)
    return c.reshape(-1, 2).astype(np.float64)


def find_board_corners(image: np.ndarray, board: BoardSpec) -> np.ndarray | None:
    """The board's inner corners in ``image``, or None when it is not found whole.

    Parameters
    ----------
    image : (H, W) or (H, W, 3) array
        The capture (grey or RGB).
    board : BoardSpec

    Returns
    -------
    (N, 2) float64 or None
        Pixel positions in the order of :meth:`BoardSpec.object_points` (up to the
        detector's choice of starting corner).

    Convention
    ----------
    Pixel centres at integer coordinates (as cv2); corners found on the 2× copy are mapped
    back by ``(p + 0.5) / 2 − 0.5``.
    """
    import cv2

    grey = _grey(image)
    sb = cv2.CALIB_CB_ACCURACY | cv2.CALIB_CB_NORMALIZE_IMAGE
    up = cv2.resize(grey, None, fx=2, fy=2, interpolation=cv2.INTER_CUBIC)
    for img, scale, flags in ((up, 2.0, sb), (up, 2.0, sb | cv2.CALIB_CB_EXHAUSTIVE),
                              (grey, 1.0, sb | cv2.CALIB_CB_EXHAUSTIVE)):
        ok, c = cv2.findChessboardCornersSB(img, board.inner, flags=flags)
        if ok:
            return (c.reshape(-1, 2).astype(np.float64) + 0.5) / scale - 0.5
    for img, scale in ((grey, 1.0), (up, 2.0)):
        c2 = _classic(img, board.inner)
        if c2 is not None:
            return (c2 + 0.5) / scale - 0.5
    return None
