"""The scene with a corrected mount pose, and a correction as the scene's mount values."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..camera import rotation_from_ypr
from ..scene import Scene
from .records import PoseCorrection

__all__ = ["scene_with_mount", "mount_correction"]


def scene_with_mount(scene: Scene, correction: PoseCorrection) -> Scene:
    """A copy of ``scene`` with the corrected mount pose (position m, angles degrees; on the
    unloaded body, :func:`mount_correction`).  Under a ``load_state`` the body stays where
    it was: its pivot is pinned to the old mount position when the scene left it to the
    mount."""
    moved = scene.with_mount(correction.position_m, correction.yaw_deg, correction.pitch_deg,
                             correction.roll_deg)
    load = scene.load_state
    if load is not None and load.pivot_m is None:
        load = load.model_copy(update={"pivot_m": scene.camera.mount.position})
    return moved.model_copy(update={"load_state": load})


def mount_correction(scene: Scene, correction: PoseCorrection) -> PoseCorrection:
    """``correction`` with its corrected pose as the scene's mount values.

    The pose search works on the camera as the scene shows it; under a ``load_state`` that
    is the camera moved with the body, so its corrected pose (``position_m`` and the
    angles, scene frame) is taken back to the unloaded body (what ``camera.mount`` holds).
    The changes (``d_*``) stay those of the camera in the scene frame.  Without a load
    state, ``correction`` itself.
    """
    load = scene.load_state
    if load is None:
        return correction
    rot = rotation_from_ypr(correction.yaw_deg, correction.pitch_deg, correction.roll_deg)
    pos, ypr = load.mount_of(np.asarray(correction.position_m), rot,
                             scene.camera.mount.position)
    return replace(correction, position_m=pos, yaw_deg=float(ypr[0]),
                   pitch_deg=float(ypr[1]), roll_deg=float(ypr[2]))
