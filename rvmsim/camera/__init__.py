"""Camera models: the fisheye lens (equidistance, Kannala-Brandt) and the mount rotation."""

from __future__ import annotations

from .fisheye import (
    FisheyeCamera,
    rotation_from_ypr,
    distort_theta,
    undistort_theta,
)

__all__ = [
    "FisheyeCamera",
    "rotation_from_ypr",
    "distort_theta",
    "undistort_theta",
]
