"""The pose search's records: each landmark predicted, found and reprojected
(:class:`LandmarkMatch`), and the mount change it gives (:class:`PoseCorrection`).

Convention
----------
Landmark positions are (u, v) px, column then row, pixel centres at integer coordinates (as
in :mod:`rvmsim.camera`); mount changes are mm and degrees in the scene frame (x driver
side, y down, z rearward), corrected poses m and degrees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LandmarkMatch", "PoseCorrection"]


@dataclass(frozen=True)
class LandmarkMatch:
    """One predicted landmark and where it was found in the capture.

    Attributes
    ----------
    name : str
        The checker corner's name (``board_inner_…``, ``<pattern>_…``).
    point : (3,) float
        The corner in the scene, m.
    predicted_px : (2,) float
        Its projection with the scene's mount pose, px.
    found_px : (2,) float or None
        Where it was found in the capture, px; None: not found.
    corrected_px : (2,) float
        Its projection with the fitted mount pose, px.
    method : str
        ``"chessboard"``, ``"local"`` or ``""`` (not found).
    ncc : float
        The match's normalised cross-correlation (1.0 for the chessboard detector).
    inlier : bool
        Used by the final least-squares pose fit.
    """

    name: str
    point: tuple[float, float, float]
    predicted_px: tuple[float, float]
    found_px: tuple[float, float] | None
    corrected_px: tuple[float, float]
    method: str
    ncc: float
    inlier: bool

    @property
    def error_before_px(self) -> float | None:
        """Distance from the prediction to the find, px (None when not found)."""
        if self.found_px is None:
            return None
        return math.dist(self.found_px, self.predicted_px)

    @property
    def error_after_px(self) -> float | None:
        """Distance from the corrected reprojection to the find, px (None when not found)."""
        if self.found_px is None:
            return None
        return math.dist(self.found_px, self.corrected_px)


@dataclass(frozen=True)
class PoseCorrection:
    """The mount pose change that best explains the capture.

    Attributes
    ----------
    d_position_mm : (3,) float
        Δx, Δy, Δz of the optical centre, scene frame, mm (Δy < 0: higher).
    d_yaw_deg, d_pitch_deg, d_roll_deg : float
        Changes of the scene's mount angles, degrees.
    sigma_position_mm, sigma_angles_deg : (3,) float
        One standard error of each, from the fit's Jacobian and residual (mm, degrees).
    position_m : (3,) float
        The corrected mount position, m.
    yaw_deg, pitch_deg, roll_deg : float
        The corrected mount angles, degrees.
    """

    d_position_mm: tuple[float, float, float]
    d_yaw_deg: float
    d_pitch_deg: float
    d_roll_deg: float
    sigma_position_mm: tuple[float, float, float]
    sigma_angles_deg: tuple[float, float, float]
    position_m: tuple[float, float, float]
    yaw_deg: float
    pitch_deg: float
    roll_deg: float

    @property
    def d_position_norm_mm(self) -> float:
        """Length of the position correction, mm."""
        return float(np.linalg.norm(self.d_position_mm))

    @property
    def max_d_angle_deg(self) -> float:
        """Largest of |Δyaw|, |Δpitch|, |Δroll|, degrees."""
        return max(abs(self.d_yaw_deg), abs(self.d_pitch_deg), abs(self.d_roll_deg))
