"""The station's geometry: the load state a car stands at, its camera there, and the
deviation of a measured camera pose from the nominal mount.

Conventions
-----------
A load state moves the body relative to the ground (:func:`rvmsim.robust.body_pose`: the
body pitched about the camera's nominal centre, then lowered), and the camera with it.  A
:class:`~rvmsim.compensation.Deviation` is the camera's pose relative to its nominal mount
in the *body* frame (angles add to the mount's yaw, pitch, roll, degrees; the position
offset, mm, adds to its position), as :class:`rvmsim.robust.MountSample`'s offsets.  So a
car whose camera deviates by ``d`` and which stands at load ``L`` has the camera
``body_pose(L) ∘ deviated_camera(d)`` in the scene (ground) frame, and the station, which
measures that camera in the ground frame, undoes the load before it computes ``d``
(:func:`deviation_of`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..camera import FisheyeCamera
from ..compensation import CompensationModel, Deviation, deviated_camera, measured_load_index
from ..robust import LoadState, Variation, body_pose, variation_from_scene
from ..scene import Scene
from ..validate import ypr_from_rotation

__all__ = ["station_load", "moved_camera", "car_camera", "deviation_of", "mount_at"]


def station_load(scene: Scene, model: CompensationModel,
                 variation: Variation | None = None) -> LoadState:
    """The load state the station measures at: the compensation model's
    ``station.measured_at`` among ``variation``'s load states (default: the scene's
    variation section; without one, the scene as modelled), else the first.

    Raises
    ------
    CompensationError
        ``measured_at`` names no load state of the variation.
    """
    var = variation if variation is not None else variation_from_scene(scene)
    names = [s.name for s in var.load_states]
    return var.load_states[measured_load_index(model, names)]


def moved_camera(camera: FisheyeCamera, pose: np.ndarray | None) -> FisheyeCamera:
    """``camera`` moved with the body by ``pose`` ((4, 4) rigid motion of the scene frame,
    :func:`rvmsim.robust.body_pose`; None: unmoved)."""
    if pose is None:
        return camera
    rot, t = pose[:3, :3], pose[:3, 3]
    return dataclasses.replace(camera, rotation=rot @ camera.rotation,
                               position=rot @ camera.position + t)


def car_camera(scene: Scene, deviation: Deviation, load: LoadState | None = None
               ) -> FisheyeCamera:
    """The camera of a car whose mount deviates by ``deviation``, standing at ``load``
    (None: as modelled), in the scene frame (full sensor)."""
    cam = deviated_camera(scene, deviation)
    return cam if load is None else moved_camera(cam, body_pose(scene, load))


def deviation_of(scene: Scene, position: np.ndarray, rotation: np.ndarray,
                 pose: np.ndarray | None = None) -> Deviation:
    """The deviation from the nominal mount of a camera measured at ``position`` (m) with
    ``rotation`` (camera-to-scene) on a car whose body stands at ``pose`` ((4, 4), None:
    unmoved): the inverse of :func:`car_camera`.

    Returns
    -------
    Deviation
        mm and degrees, in the body frame (see the module's conventions).
    """
    rot, pos = np.asarray(rotation, np.float64), np.asarray(position, np.float64)
    if pose is not None:
        r_b, t = pose[:3, :3], pose[:3, 3]
        rot, pos = r_b.T @ rot, r_b.T @ (pos - t)
    m = scene.camera.mount
    angles = ypr_from_rotation(rot) - np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    angles = (angles + 180.0) % 360.0 - 180.0
    offset = (pos - np.asarray(m.position, np.float64)) * 1000.0
    return Deviation.from_offsets([*offset, *angles])


def mount_at(scene: Scene, camera: FisheyeCamera) -> Scene:
    """``scene`` with its camera mounted at ``camera``'s pose (position m; the angles that
    make its rotation, :func:`rvmsim.validate.ypr_from_rotation`)."""
    yaw, pitch, roll = (float(a) for a in ypr_from_rotation(camera.rotation))
    mount = scene.camera.mount.model_copy(update={
        "position": tuple(float(p) for p in camera.position), "yaw_deg": yaw,
        "pitch_deg": pitch, "roll_deg": roll})
    return scene.model_copy(update={"camera": scene.camera.model_copy(update={"mount": mount})})
