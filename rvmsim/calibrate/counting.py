"""The other counting of a checkerboard: when the board of ``--board`` is not found, whether
the captures show a board of one more or one fewer inner corners each way (squares counted
for inner corners, or the reverse), found quickly, for a one-line hint."""

from __future__ import annotations

import time
from typing import Sequence

import cv2
import numpy as np

from .board import BoardSpec

__all__ = ["other_counting", "counting_hint", "HINT_CAPTURES", "HINT_BUDGET_S"]

#: Captures the other counting is tried on, at most.
HINT_CAPTURES = 3
#: Seconds the other counting may take, at most (checked between detector calls).
HINT_BUDGET_S = 20.0
#: The longer side of the copy the quick detector works on, px.
QUICK_SIDE_PX = 1280


def _quick_found(grey: np.ndarray, inner: tuple[int, int]) -> bool:
    """Whether ``cv2.findChessboardCornersSB`` (no exhaustive search) finds a board of
    exactly ``inner`` corners on a copy of ``grey`` scaled to a longer side of
    :data:`QUICK_SIDE_PX` (at most 2× up)."""

    scale = min(2.0, QUICK_SIDE_PX / max(grey.shape))
    img = grey if abs(scale - 1) < 0.05 else cv2.resize(
        grey, None, fx=scale, fy=scale,
        interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_CUBIC)
    ok, _ = cv2.findChessboardCornersSB(img, inner, flags=cv2.CALIB_CB_NORMALIZE_IMAGE)
    return bool(ok)


def other_counting(greys: Sequence[np.ndarray], board: BoardSpec) -> tuple[int, int] | None:
    """The inner corners (one fewer, or one more, each way than ``board``'s) of a board
    found in any of the first :data:`HINT_CAPTURES` of ``greys`` (grey captures), or None;
    gives up after :data:`HINT_BUDGET_S` seconds."""
    c, r = board.inner
    # The larger first: cv2's detector can find a smaller grid inside a board, never a
    # larger one.
    sizes = [(c + 1, r + 1), *([(c - 1, r - 1)] if min(c, r) > 2 else [])]
    t0 = time.monotonic()
    for grey in greys[:HINT_CAPTURES]:
        for size in sizes:
            if time.monotonic() - t0 > HINT_BUDGET_S:
                return None
            if _quick_found(grey, size):
                return size
    return None


def counting_hint(board: BoardSpec, found: tuple[int, int], spec: str) -> str:
    """The hint for a board that looks like ``found`` inner corners when ``board`` (from
    ``--board spec``) was given, e.g. ``the board looks like 7x9 inner corners (8x10
    squares); you gave 8x10 inner corners, which counts its squares: pass --board
    7x9:0.05``."""
    a, b = found
    c, r = board.inner
    by_squares = spec.strip().split(":")[0].strip().lower() == "squares"
    shown = f"squares:{c + 1}x{r + 1}" if by_squares else f"{c}x{r} inner corners"
    if by_squares:
        reason = "one more each way" if a < c else "which counts its inner corners"
    else:
        reason = "which counts its squares" if a < c else "one fewer each way"
    why = f"you gave {shown}, {reason}"
    return (f"the board looks like {a}x{b} inner corners ({a + 1}x{b + 1} squares); {why}: "
            f"pass --board {a}x{b}:{board.square_size:g} (or squares:{a + 1}x{b + 1}:"
            f"{board.square_size:g})")
