"""The camera's mount on the vehicle: the scene and camera frames and the mount rotation.

Conventions
-----------
Scene frame (the paper's, section III-A): X toward the driver's side, Y toward the ground,
Z toward the rear of the vehicle; origin on the ground, on the vehicle centre line, in the
vertical plane through the rearmost point of the rear bumper.  Units: metres.  A point at
height ``h`` above the ground has ``Y = -h``.

Camera frame (OpenCV's): x to the right of the image, y down the image, z along the optical
axis.  With yaw = pitch = roll = 0 the camera looks straight rearward and its axes coincide
with the scene axes (x = X, y = Y, z = Z).

Mount angles, in degrees, applied as ``R_cam_to_scene = Ry(yaw) @ Rx(-pitch) @ Rz(roll)``:

* ``pitch`` > 0 turns the optical axis down toward the ground;
* ``yaw`` > 0 turns the optical axis toward +X (the driver's side);
* ``roll`` > 0 turns the camera's x axis toward its y axis about the optical axis.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rotation_from_ypr", "ypr_from_rotation"]


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_from_ypr(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """Camera-to-scene rotation from mount angles.

    Parameters
    ----------
    yaw_deg, pitch_deg, roll_deg : float
        Mount angles in degrees (see the module docstring for the signs).

    Returns
    -------
    R : (3, 3) float64
        Rotation whose columns are the camera's x, y, z axes in scene coordinates.
    """
    return (
        _rot_y(np.radians(yaw_deg)) @ _rot_x(-np.radians(pitch_deg)) @ _rot_z(np.radians(roll_deg))
    )


def ypr_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Mount yaw, pitch, roll (degrees) of a camera-to-scene rotation: the inverse of
    :func:`rotation_from_ypr` (``Ry(yaw) @ Rx(-pitch) @ Rz(roll)``; pitch in [−90°, 90°])."""
    r = np.asarray(rotation, dtype=np.float64)
    pitch = np.arcsin(np.clip(r[1, 2], -1.0, 1.0))
    yaw = np.arctan2(r[0, 2], r[2, 2])
    roll = np.arctan2(r[1, 0], r[1, 1])
    return np.degrees([yaw, pitch, roll])
