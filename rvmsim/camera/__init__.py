"""Camera models: the fisheye camera, its lens models (equidistance, Kannala-Brandt; one
module each, on the :class:`LensModel` interface, registered by name in :data:`LENS_MODELS`)
and the mount rotation."""

from __future__ import annotations

from .lens import LENS_MODELS, LensFactory, LensModel, make_lens, newton_undistort, register_lens_model
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
    "LensFactory",
    "LENS_MODELS",
    "make_lens",
    "register_lens_model",
    "newton_undistort",
    "Equidistance",
    "KannalaBrandt",
    "distort_theta",
    "distort_theta_derivative",
    "undistort_theta",
]
