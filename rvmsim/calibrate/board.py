"""The calibration board of ``rvmsim calibrate``: its inner-corner grid and square size.

``--board`` is either ``COLSxROWS:SQUARE`` (inner corners across and down, square side in
metres, e.g. ``9x7:0.03``) or a scene file whose ``test_site.board`` is the board used
(its ``squares`` minus one inner corners each way).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputFileError, RvmsimError

__all__ = ["BoardSpec", "parse_board_spec", "CalibrationInputError"]


class CalibrationInputError(InputFileError):
    """A capture, calibration file or board given to ``rvmsim calibrate`` is unusable."""


@dataclass(frozen=True)
class BoardSpec:
    """A checkerboard as the corner detector sees it.

    Attributes
    ----------
    inner : (int, int)
        Inner corners (columns across, rows down); each at least 2.
    square_size : float
        Side of a square, metres.
    """

    inner: tuple[int, int]
    square_size: float

    def object_points(self) -> np.ndarray:
        """(N, 3) float64 board points, metres, row by row (x fastest), z = 0.

        Convention
        ----------
        The board's own frame: x along a row, y down the columns, z = 0 on the board; the
        order is that of ``cv2.findChessboardCorners`` for pattern size ``inner``.
        """
        cols, rows = self.inner
        x, y = np.meshgrid(np.arange(cols), np.arange(rows))
        pts = np.stack([x.ravel(), y.ravel(), np.zeros(cols * rows)], axis=1)
        return pts * self.square_size


_SPEC = re.compile(r"^\s*(\d+)\s*[xX]\s*(\d+)\s*:\s*([0-9.eE+-]+)\s*$")


def parse_board_spec(spec: str) -> BoardSpec:
    """The board of ``--board SPEC``: ``COLSxROWS:SQUARE`` (inner corners, metres) or a
    scene file (its ``test_site.board``).

    Raises
    ------
    RvmsimError
        One line naming ``--board`` when the spec is neither.
    """
    m = _SPEC.match(spec)
    if m is not None:
        cols, rows, size = int(m.group(1)), int(m.group(2)), float(m.group(3))
        if not (2 <= cols <= 200 and 2 <= rows <= 200):
            raise RvmsimError(f"--board {spec}: inner corners must be 2..200 each way")
        if not (0 < size <= 10):  # also refuses nan
            raise RvmsimError(f"--board {spec}: the square size must be in (0, 10] m")
        return BoardSpec((cols, rows), size)
    path = Path(spec)
    if path.suffix.lower() in (".yaml", ".yml") and path.is_file():
        from ..scene import load_scene

        board = load_scene(path).test_site.board
        return BoardSpec((board.squares[0] - 1, board.squares[1] - 1), board.square_size)
    raise RvmsimError(f"--board {spec}: expected COLSxROWS:SQUARE (inner corners, metres, "
                      "e.g. 9x7:0.03) or a scene file")
