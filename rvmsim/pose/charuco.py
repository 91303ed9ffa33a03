"""ChArUco boards: their inner corners found by their markers (``cv2.aruco``).

A ChArUco board's markers name its inner corners, so a detection needs no predicted pose
and has no orientation or one-square ambiguity.  :func:`detect_charuco` runs
``cv2.aruco.CharucoDetector`` (which refines each corner with a window kept clear of the
markers) on the capture, upsampled where the squares are small, and returns the corners
as the board's inner-corner indices.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  Inner corner (i, j): i along the board's width (u), j along its
height (v), from the corner at −u, −v (:mod:`.board`).  cv2's ChArUco corner id k is its
inner corner (k mod (cols − 1), k div (cols − 1)) counted from the top of its board image,
whose top row is the board's +v edge (as :mod:`rvmsim.scene` draws it): so
i = k mod (cols − 1) and j = rows − 2 − k div (cols − 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


__all__ = ["CharucoPattern", "detect_charuco", "UPSAMPLE"]

#: Upsampling factors tried, in order; the one that finds the most corners wins.
UPSAMPLE = (2, 1, 3)
#: Fewer corners than this found is no detection.
MIN_CORNERS = 6


@dataclass(frozen=True)
class CharucoPattern:
    """A ChArUco board as ``cv2.aruco.CharucoBoard`` sees it.

    Attributes
    ----------
    squares : (cols, rows) int
        Squares along the board's width and height.
    square_size, marker_size : float
        m.
    dictionary : str
        A ``cv2.aruco`` dictionary name, e.g. ``"DICT_4X4_50"``.
    """

    squares: tuple[int, int]
    square_size: float
    marker_size: float
    dictionary: str

    def cv2_board(self) -> cv2.aruco.CharucoBoard:
        """The ``cv2.aruco.CharucoBoard``, with cv2's legacy square order when ``rows`` is
        even, as the scene draws it."""

        dic = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))
        board = cv2.aruco.CharucoBoard(self.squares, self.square_size, self.marker_size, dic)
        board.setLegacyPattern(self.squares[1] % 2 == 0)
        return board

    def corner_ij(self, ids: np.ndarray) -> np.ndarray:
        """cv2's ChArUco corner ids (K,) as inner-corner indices (K, 2) int (see the module's
        convention)."""
        cols, rows = self.squares
        ids = np.asarray(ids, dtype=int).ravel()
        return np.stack([ids % (cols - 1), rows - 2 - ids // (cols - 1)], axis=1)

    def board_points(self, ij: np.ndarray) -> np.ndarray:
        """The points (K, 3) m, in cv2's board frame (``getChessboardCorners``), of the
        inner corners ``ij`` (K, 2): the inverse of :meth:`corner_ij`, then cv2's points."""
        cols, rows = self.squares
        ij = np.asarray(ij, dtype=int)
        ids = (rows - 2 - ij[:, 1]) * (cols - 1) + ij[:, 0]
        return np.asarray(self.cv2_board().getChessboardCorners(), np.float64)[ids]


def detect_charuco(grey_u8: np.ndarray, pattern: CharucoPattern,
                   upsample: tuple[int, ...] = UPSAMPLE) -> tuple[np.ndarray, np.ndarray] | None:
    """The board's inner corners that ``cv2.aruco.CharucoDetector`` finds in an image.

    Parameters
    ----------
    grey_u8 : (H, W) uint8
        Grey image (a capture, or a perspective view of one).
    pattern : CharucoPattern
    upsample : tuple of int
        Factors to run the detector at (cubic upsampling); the one finding the most corners
        wins.

    Returns
    -------
    (ij, px) or None
        Inner-corner indices (K, 2) int and their pixels (K, 2) float, px; None when fewer
        than :data:`MIN_CORNERS` are found.

    Convention
    ----------
    Upsampled pixel centres sit at (p + ½)·f − ½; the corners are given back in ``grey_u8``'s
    pixels.
    """

    detector = cv2.aruco.CharucoDetector(pattern.cv2_board())
    best: tuple[np.ndarray, np.ndarray] | None = None
    for f in upsample:
        img = grey_u8 if f == 1 else cv2.resize(grey_u8, None, fx=f, fy=f,
                                                interpolation=cv2.INTER_CUBIC)
        corners, ids, _, _ = detector.detectBoard(img)
        if ids is None or len(ids) < MIN_CORNERS:
            continue
        px = (np.asarray(corners, np.float64).reshape(-1, 2) + 0.5) / f - 0.5
        if best is None or len(px) > len(best[1]):
            best = (pattern.corner_ij(ids), px)
    return best
