"""A scene's load state: the body lowered and pitched relative to the ground, exactly as
``rvmsim robustness`` applies a load state to a sample (so that any sample can be written
as a scene and rendered in full).

Example (a scene file's top level)::

    load_state: {name: full load, height_mm: -45, pitch_deg: 0.9}

Conventions
-----------
The body (the camera and every vehicle part: bumper, garnish, trunk, extra meshes) pitches
rear-down by ``pitch_deg`` about ``pivot_m`` (default: the camera's mount position, its
nominal centre), then drops by ``-height_mm`` (``height_mm`` < 0 lowers it); the ground and
the test site stay.  As a rigid motion of the scene frame (Y toward the ground, metres)::

    p ↦ R_b · (p − pivot) + pivot + (0, −height_mm / 1000, 0),   R_b = rotation_from_ypr(0, pitch_deg, 0)

The camera's ``mount`` is its pose on the unloaded body: under the load its rotation is
``R_b · R(yaw, pitch, roll)`` and its centre the mount position moved as above.  A pivot
other than the mount position matters when the mount was moved from the point the body
turns about (a robustness sample with a position offset: the body turns about the nominal
centre, not the sample's camera).
"""

from __future__ import annotations

import dataclasses
from typing import Annotated

import numpy as np
from pydantic import Field

from ..camera import FisheyeCamera, rotation_from_ypr, ypr_from_rotation
from .fields import Vec3, _Model

__all__ = ["SceneLoadState", "body_motion", "MAX_LOAD_HEIGHT_MM", "MAX_LOAD_PITCH_DEG"]

#: Largest drop or rise of the body (mm) and body pitch (degrees), as a variation's load
#: states (:class:`rvmsim.scene.LoadStateSpec`).
MAX_LOAD_HEIGHT_MM = 300.0
MAX_LOAD_PITCH_DEG = 10.0


def body_motion(height_mm: float, pitch_deg: float, pivot_m: np.ndarray) -> np.ndarray:
    """The (4, 4) rigid motion of the body under a load (see the module docstring).

    Parameters
    ----------
    height_mm : float
        Change of the body's height, mm (negative: lower).
    pitch_deg : float
        Body pitch, degrees (rear down > 0).
    pivot_m : (3,) float
        The point the body pitches about, scene frame, m.

    Returns
    -------
    (4, 4) float
        Homogeneous transform of scene points (m).
    """
    pivot = np.asarray(pivot_m, dtype=np.float64)
    rb = rotation_from_ypr(0.0, pitch_deg, 0.0)
    pose = np.eye(4)
    pose[:3, :3] = rb
    pose[:3, 3] = pivot - rb @ pivot + np.array([0.0, -height_mm / 1000.0, 0.0])
    return pose


class SceneLoadState(_Model):
    """The scene's body under a load: ``height_mm`` (mm, negative lowers it), ``pitch_deg``
    (degrees, rear down > 0) and the point it pitches about, ``pivot_m`` (scene frame, m;
    default the camera's mount position).  ``name`` is for people (``curb``, ``full load``)."""

    name: Annotated[str, Field(min_length=1, max_length=40)] = "loaded"
    height_mm: Annotated[float, Field(ge=-MAX_LOAD_HEIGHT_MM, le=MAX_LOAD_HEIGHT_MM)] = 0.0
    pitch_deg: Annotated[float, Field(ge=-MAX_LOAD_PITCH_DEG, le=MAX_LOAD_PITCH_DEG)] = 0.0
    pivot_m: Vec3 | None = None

    def pivot(self, mount_position: Vec3) -> np.ndarray:
        """The pivot, m: ``pivot_m``, else ``mount_position``."""
        return np.asarray(self.pivot_m if self.pivot_m is not None else mount_position,
                          dtype=np.float64)

    def motion(self, mount_position: Vec3) -> np.ndarray:
        """The body's (4, 4) rigid motion (:func:`body_motion`) for a camera mounted at
        ``mount_position`` (m)."""
        return body_motion(self.height_mm, self.pitch_deg, self.pivot(mount_position))

    def camera(self, camera: FisheyeCamera, mount_position: Vec3) -> FisheyeCamera:
        """``camera`` (its pose on the unloaded body) moved with the body."""
        pose = self.motion(mount_position)
        return dataclasses.replace(
            camera, rotation=pose[:3, :3] @ camera.rotation,
            position=pose[:3, :3] @ np.asarray(camera.position) + pose[:3, 3])

    def mount_of(self, position_m: np.ndarray, rotation: np.ndarray,
                 mount_position: Vec3) -> tuple[tuple[float, float, float], np.ndarray]:
        """The mount (position m; yaw, pitch, roll degrees) on the unloaded body of a camera
        seen at ``position_m`` with camera-to-scene ``rotation`` under this load: the inverse
        of :meth:`camera`, with the pivot of a camera mounted at ``mount_position``."""
        pose = self.motion(mount_position)
        rb = pose[:3, :3]
        p = rb.T @ (np.asarray(position_m, dtype=np.float64) - pose[:3, 3])
        return (float(p[0]), float(p[1]), float(p[2])), ypr_from_rotation(rb.T @ rotation)
