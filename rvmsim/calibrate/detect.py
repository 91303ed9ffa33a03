"""Board corners in a fisheye capture.

A checkerboard: OpenCV's sector-based detector, then the classic detector with sub-pixel
refinement, each on the capture and on a 2× upsampled copy (small boards); the board is
found whole or not at all.  A ChArUco board: its markers (``cv2.aruco.CharucoDetector``,
:func:`rvmsim.pose.detect_charuco`), so a view may hold any part of it, down
to :data:`~.intrinsics.MIN_VIEW_CORNERS` corners not all on one line.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..pose import detect_charuco
from .board import BoardSpec
from .intrinsics import MIN_VIEW_CORNERS, BoardView

__all__ = ["find_board_corners", "find_board_view"]


def _grey(image: np.ndarray) -> np.ndarray:

    if image.ndim == 3:
        image = cv2.cvtColor(np.ascontiguousarray(image[..., :3]), cv2.COLOR_RGB2GRAY)
    if image.dtype == np.uint8:
        return image
    lo, hi = float(image.min()), float(image.max())
    return ((image.astype(np.float64) - lo) * (255.0 / max(hi - lo, 1e-12))).astype(np.uint8)


def _classic(grey: np.ndarray, inner: tuple[int, int]) -> np.ndarray | None:
    """cv2.findChessboardCorners + cornerSubPix, (N, 2) float64 or None."""

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


def find_board_view(image: np.ndarray, board: BoardSpec, name: str) -> BoardView | None:
    """The board's corners in ``image`` as a calibration view, or None when not found.

    A checkerboard is found whole (:func:`find_board_corners`).  A ChArUco board's corners
    are found by its markers, each with its board point (cv2's
    ``CharucoBoard.getChessboardCorners``), and a view needs
    :data:`~.intrinsics.MIN_VIEW_CORNERS` of them spanning two rows and two columns.

    Convention
    ----------
    Pixel centres at integer coordinates (as cv2).
    """
    if board.charuco is None:
        corners = find_board_corners(image, board)
        return None if corners is None else BoardView(name, corners)

    det = detect_charuco(_grey(image), board.charuco)
    if det is None:
        return None
    ij, px = det
    if len(px) < MIN_VIEW_CORNERS or len(set(ij[:, 0])) < 2 or len(set(ij[:, 1])) < 2:
        return None
    return BoardView(name, px, board.charuco.board_points(ij))
