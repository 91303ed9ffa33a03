"""A pose search that could not finish, and which of its steps failed.

Steps, in order: ``detection`` (too few landmarks found in the capture), ``correspondence``
(found corners that cannot be told from a one-square alias), ``pose fit`` (the corners do
not determine the pose).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..errors import RvmsimError
from .records import LandmarkMatch

__all__ = ["PoseFailure", "Step"]

Step = Literal["detection", "correspondence", "pose fit"]


class PoseFailure(RvmsimError):
    """One-line error naming the failed step, with what was found so far.

    Parameters
    ----------
    step : {"detection", "correspondence", "pose fit"}
    message : str
        What went wrong (starts with the capture's name).
    images : dict of str to (H, W, 3) uint8, optional
        Pictures (``overlay``, ``edges``, ``landmarks``) to write for the user (a caller
        that draws them, :class:`rvmsim.validate.ValidationFailure`).
    found : (N, 2) float, optional
        The landmarks found before the failure (NaN: not found), px.
    landmarks : tuple of LandmarkMatch
        The usable landmarks predicted at the scene's pose, with where they were found
        (none fitted: ``corrected_px`` is the prediction); :func:`rvmsim.pose.find_mount`
        sets them, for the pictures.
    board_corners : (K, 2) float, optional
        The corners of the largest grid the board search found, px.
    board_outlines : tuple of (M, 2) float
        For an ambiguous lattice, the board's outline (px) at the pick and at its rival.
    """

    def __init__(self, step: Step, message: str, images: dict[str, np.ndarray] | None = None,
                 found: np.ndarray | None = None, *,
                 landmarks: tuple[LandmarkMatch, ...] = (),
                 board_corners: np.ndarray | None = None,
                 board_outlines: tuple[np.ndarray, ...] = ()) -> None:
        super().__init__(f"{message} (step failed: {step})")
        self.step: Step = step
        self.detail = message
        self.images = dict(images or {})
        self.found = found
        self.landmarks = landmarks
        self.board_corners = board_corners
        self.board_outlines = board_outlines
