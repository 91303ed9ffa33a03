"""The calibration board of ``rvmsim calibrate``: its inner-corner grid and square size.

``--board`` is ``COLSxROWS:SQUARE`` (a checkerboard: inner corners across and down, square
side in metres, e.g. ``9x7:0.03``; ``inner:COLSxROWS:SQUARE`` says so explicitly, and
``squares:COLSxROWS:SQUARE`` counts squares instead, e.g. ``squares:10x8:0.03`` for the
same board), ``charuco:COLSxROWS:SQUARE:MARKER[:DICTIONARY]`` (a
ChArUco board as ``cv2.aruco.CharucoBoard`` counts it: *squares* across and down, square
and marker side in metres, a ``cv2.aruco`` dictionary, default ``DICT_4X4_50``; e.g.
``charuco:7x10:0.08:0.06``), or a scene file whose ``test_site.board`` is the board used
(its ``squares`` minus one inner corners each way; ChArUco when its pattern is).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from ..errors import InputFileError, RvmsimError
from ..scene import load_scene
from ..scene.board import PatternBoard
from ..pose import CharucoPattern

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
    charuco : CharucoPattern or None
        The markers of a ChArUco board (its corners are then found by them, and a view
        may hold only some of them).
    """

    inner: tuple[int, int]
    square_size: float
    charuco: CharucoPattern | None = None

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

    def describe(self) -> str:
        """The board in both countings, e.g. ``7x9 inner corners (8x10 squares)``, or for a
        ChArUco board ``ChArUco 7x10 squares (6x9 inner corners)``."""
        c, r = self.inner
        if self.charuco is not None:
            return f"ChArUco {c + 1}x{r + 1} squares ({c}x{r} inner corners)"
        return f"{c}x{r} inner corners ({c + 1}x{r + 1} squares)"


_SPEC = re.compile(r"^\s*(?:(inner|squares)\s*:\s*)?(\d+)\s*[xX]\s*(\d+)\s*:"
                   r"\s*([0-9.eE+-]+)\s*$", re.IGNORECASE)
_CHARUCO = re.compile(r"^\s*charuco\s*:\s*(\d+)\s*[xX]\s*(\d+)\s*:\s*([0-9.eE+-]+)\s*:"
                      r"\s*([0-9.eE+-]+)\s*(?::\s*(\w+)\s*)?$", re.IGNORECASE)


def _charuco_spec(spec: str, m: re.Match[str]) -> BoardSpec:
    """The ChArUco board of ``charuco:COLSxROWS:SQUARE:MARKER[:DICTIONARY]``, checked as a
    scene's board is (marker below the square, a dictionary with enough markers)."""

    try:
        board = PatternBoard(pattern="charuco", squares=(int(m.group(1)), int(m.group(2))),
                             square_size=float(m.group(3)), marker_size=float(m.group(4)),
                             aruco_dictionary=m.group(5) or "DICT_4X4_50")
    except ValidationError as err:
        msg = err.errors()[0]["msg"].removeprefix("Value error, ")
        raise RvmsimError(f"--board {spec}: {msg}") from None
    return _from_pattern_board(board)


def _from_pattern_board(board: PatternBoard) -> BoardSpec:
    """The calibration board of a scene's ``test_site.board``."""
    charuco = None
    if board.pattern == "charuco" and board.marker_size is not None:
        charuco = CharucoPattern((board.squares[0], board.squares[1]), board.square_size,
                                 board.marker_size, board.aruco_dictionary)
    return BoardSpec((board.squares[0] - 1, board.squares[1] - 1), board.square_size, charuco)


def _scene_board(path: Path) -> BoardSpec:
    """The board of a scene file's ``test_site.board``.

    Raises
    ------
    CalibrationInputError
        The scene gives no ``test_site.board`` (the default board is not a board anybody
        captured), or its board is disabled (``enabled: false``): naming the file and key.
    """

    site = load_scene(path).test_site
    if "board" not in site.model_fields_set:
        raise CalibrationInputError(str(path), "test_site.board", "the scene gives no board "
                                    "(--board SCENE calibrates with the scene's board)")
    if not site.board.enabled:
        raise CalibrationInputError(str(path), "test_site.board.enabled", "the board is "
                                    "disabled in this scene: give the board captured with "
                                    "--board COLSxROWS:SQUARE, or enable it")
    return _from_pattern_board(site.board)


def parse_board_spec(spec: str) -> BoardSpec:
    """The board of ``--board SPEC``: ``[inner:]COLSxROWS:SQUARE`` (inner corners, metres),
    ``squares:COLSxROWS:SQUARE`` (squares), ``charuco:COLSxROWS:SQUARE:MARKER[:DICT]``
    (squares) or a scene file (its ``test_site.board``).

    Raises
    ------
    RvmsimError
        One line naming ``--board`` when the spec is neither.
    """
    c = _CHARUCO.match(spec)
    if c is not None:
        return _charuco_spec(spec, c)
    m = _SPEC.match(spec)
    if m is not None:
        squares = (m.group(1) or "").lower() == "squares"
        cols, rows, size = int(m.group(2)), int(m.group(3)), float(m.group(4))
        if squares:
            if not (3 <= cols <= 201 and 3 <= rows <= 201):
                raise RvmsimError(f"--board {spec}: squares must be 3..201 each way")
            cols, rows = cols - 1, rows - 1
        if not (2 <= cols <= 200 and 2 <= rows <= 200):
            raise RvmsimError(f"--board {spec}: inner corners must be 2..200 each way")
        if not (0 < size <= 10):  # also refuses nan
            raise RvmsimError(f"--board {spec}: the square size must be in (0, 10] m")
        return BoardSpec((cols, rows), size)
    path = Path(spec)
    if path.suffix.lower() in (".yaml", ".yml") and path.is_file():
        return _scene_board(path)
    raise RvmsimError(f"--board {spec}: expected COLSxROWS:SQUARE (inner corners, metres, "
                      "e.g. 9x7:0.03), squares:COLSxROWS:SQUARE (squares, e.g. "
                      "squares:10x8:0.03), charuco:COLSxROWS:SQUARE:MARKER[:DICTIONARY] "
                      "(squares, metres) or a scene file")
