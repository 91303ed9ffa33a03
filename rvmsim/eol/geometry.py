"""The station's geometry: the load state a car stands in, its camera there, and the
deviation of a measured camera pose from the design pose.

Conventions
-----------
A :class:`~rvmsim.compensation.Deviation` is a camera pose relative to the scene's mount
(angles add to its yaw, pitch, roll, degrees; the position offset, mm, adds to its
position).  A load state moves the body relative to the ground (:func:`rvmsim.robust.body_pose`:
the body pitched about the camera's nominal centre, then lowered), and the camera with it:
a car whose mount deviates by ``d`` and which stands in load state ``L`` has the camera
``body_pose(L) ∘ deviated_camera(d)`` in the scene (ground) frame (:func:`car_camera`).
The station measures that camera against the ground and compares it with the design pose
(:func:`deviation_of`): it reads ``loaded_deviation(d, L)``
(:func:`rvmsim.compensation.loaded_deviation`), and the law corrects that, as
``rvmsim robustness --compensation`` models the station.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..camera import FisheyeCamera, ypr_from_rotation
from ..compensation import CompensationModel, Deviation, deviated_camera, measured_load_index
from ..robust import LoadState, Variation, body_pose, variation_from_scene
from ..scene import Scene

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


def deviation_of(scene: Scene, position: np.ndarray, rotation: np.ndarray) -> Deviation:
    """The deviation from the design pose (the scene's mount) of a camera measured at
    ``position`` (m, scene frame) with ``rotation`` (camera-to-scene): what the station
    reads (see the module's conventions).

    Returns
    -------
    Deviation
        mm and degrees.
    """
    rot, pos = np.asarray(rotation, np.float64), np.asarray(position, np.float64)
    m = scene.camera.mount
    angles = ypr_from_rotation(rot) - np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    angles = (angles + 180.0) % 360.0 - 180.0
    offset = (pos - np.asarray(m.position, np.float64)) * 1000.0
    return Deviation.from_offsets([*offset, *angles])


def mount_at(scene: Scene, camera: FisheyeCamera) -> Scene:
    """``scene`` with its camera mounted at ``camera``'s pose (position m; the angles that
    make its rotation, :func:`rvmsim.camera.ypr_from_rotation`)."""
    yaw, pitch, roll = (float(a) for a in ypr_from_rotation(camera.rotation))
    return scene.with_mount(camera.position, yaw, pitch, roll)
