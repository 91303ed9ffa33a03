"""Pictures of a pose search for people: the landmarks predicted and found, the board the
search found, and a capture blended with a frame.

Convention
----------
Pictures are (H, W, 3) uint8 RGB; marker positions are (u, v) px with pixel centres at
integer coordinates, rounded to the nearest pixel for drawing.
"""

from __future__ import annotations

import cv2
import numpy as np

from .records import LandmarkMatch

__all__ = ["blend", "board_picture", "landmark_picture"]


def blend(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The 50/50 mix of two uint8 images of one shape (rounded down)."""
    return ((a.astype(np.uint16) + b.astype(np.uint16)) // 2).astype(np.uint8)


def _px(p: np.ndarray | tuple[float, float]) -> tuple[int, int]:
    """A pixel position for cv2's drawing functions."""
    return int(round(float(p[0]))), int(round(float(p[1])))


def landmark_picture(capture: np.ndarray, matches: tuple[LandmarkMatch, ...]) -> np.ndarray:
    """The capture with the landmarks drawn.

    Predicted (red +; red line from the prediction to the find drawn 5× longer so small
    errors show), found inliers (green o), outliers (orange x), corrected reprojection of
    the inliers (cyan dot).
    """

    out = capture.copy()
    for m in matches:
        p = np.array(m.predicted_px)
        if m.found_px is None:
            cv2.drawMarker(out, _px(p), (255, 60, 60), cv2.MARKER_CROSS, 6, 1)
            continue
        f = np.array(m.found_px)
        tip = f + 4.0 * (f - p)
        cv2.line(out, _px(p), _px(tip), (255, 60, 60), 1, cv2.LINE_AA)
        if m.inlier:
            cv2.circle(out, _px(f), 4, (40, 230, 40), 1, cv2.LINE_AA)
            cv2.circle(out, _px(m.corrected_px), 1, (0, 220, 255), -1)
        else:
            cv2.drawMarker(out, _px(f), (255, 150, 0), cv2.MARKER_TILTED_CROSS, 9, 2)
    return out


def board_picture(capture: np.ndarray, corners: np.ndarray | None,
                  outlines: tuple[np.ndarray, ...] = ()) -> np.ndarray:
    """The capture with what the board search found: the detector's corners (yellow o) and
    the outlines of the board where the readings of them put it (the first green, the others
    magenta: an ambiguous lattice's rivals).  ``corners`` (K, 2) px; each outline (M, 2) px,
    a closed polyline."""

    out = capture.copy()
    for k, line in enumerate(outlines):
        colour = (40, 230, 40) if k == 0 else (255, 0, 255)
        pts = np.round(line).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(out, [pts], True, colour, 2 if k == 0 else 1, cv2.LINE_AA)
    for p in [] if corners is None else corners:
        cv2.circle(out, _px(p), 3, (255, 230, 0), 1, cv2.LINE_AA)
    return out
