"""Camera models: the fisheye camera, its lens models (equidistance, Kannala-Brandt; one
module each, on the :class:`LensModel` interface) and the mount rotation."""

from __future__ import annotations

from .lens import LensModel, newton_undistort
from .equidistance import Equidistance
from .kannala_brandt import (
    KannalaBrandt,
    distort_theta,
    distort_theta_derivative,
    undistort_theta,
)
from .mount import rotation_from_ypr, ypr_from_rotation
from .fisheye import FisheyeCamera

__all__ = [
    "FisheyeCamera",
    "rotation_from_ypr",
    "ypr_from_rotation",
    "LensModel",
    "newton_undistort",
    "Equidistance",
    "KannalaBrandt",
    "distort_theta",
    "distort_theta_derivative",
    "undistort_theta",
]
