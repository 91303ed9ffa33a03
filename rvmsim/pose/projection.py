"""Scene points to pixels at a corrected mount pose: what the matching and the fit share.

A *pose correction* ``x`` is a (6,) float vector: Δx, Δy, Δz of the optical centre (scene
frame, m) and Δyaw, Δpitch, Δroll of the scene's mount angles (degrees).

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`; ``rotation`` maps camera axes to scene axes (columns are the camera's
axes in the scene frame), as ``FisheyeCamera.rotation``.
"""

from __future__ import annotations

import numpy as np

from ..camera import FisheyeCamera, rotation_from_ypr

__all__ = ["project", "corrected_pose"]


def project(camera: FisheyeCamera, position: np.ndarray, rotation: np.ndarray,
            points: np.ndarray) -> np.ndarray:
    """Pixels of scene ``points`` through ``camera``'s lens at another pose (no FOV test).

    Parameters
    ----------
    camera : FisheyeCamera
        Intrinsics and lens (its own pose is not used).
    position : (3,) float
        Optical centre in the scene, m.
    rotation : (3, 3) float
        Camera-to-scene rotation.
    points : (N, 3) float
        Scene points, m.

    Returns
    -------
    (N, 2) float
        Pixel coordinates, px.
    """
    return np.asarray(camera.project_rays((points - position) @ rotation)[0])


def corrected_pose(camera: FisheyeCamera, ypr0_deg: np.ndarray,
                   x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position m, rotation) of ``camera`` after the pose correction ``x``.

    Parameters
    ----------
    camera : FisheyeCamera
        The scene's camera; ``camera.position`` is the uncorrected optical centre.
    ypr0_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees.
    x : (6,) float
        The correction (see the module docstring).
    """
    return camera.position + x[:3], rotation_from_ypr(*(ypr0_deg + x[3:]))
