"""Synthetic captures for the station: the station scene rendered from a car's camera.

A car whose camera mount deviates by a :class:`~rvmsim.compensation.Deviation` and which
stands at a load state sees the station (:func:`rvmsim.scene.station_scene`) from
:func:`~.geometry.car_camera`; :func:`synthetic_capture` renders that frame through the
render cache (keyed on the scene, the pose and the body pose), for tests, benchmarks and
trying a station's design before it is built.
"""

from __future__ import annotations

from ..compensation import Deviation
from ..render import FisheyeImages
from ..robust import LoadState, body_pose
from ..scene import Scene, station_scene
from .frames import PoseRenderer
from .geometry import car_camera

__all__ = ["synthetic_capture"]


def synthetic_capture(scene: Scene, deviation: Deviation, load: LoadState | None = None, *,
                      progress: bool = False) -> FisheyeImages:
    """The station as the camera of a car deviating by ``deviation`` (mm, degrees; body
    frame) and standing at ``load`` (None: as modelled) sees it, full sensor.

    Returns
    -------
    FisheyeImages
        ``color`` is the capture ((H, W, 3) uint8); ``labels`` and ``camera`` the truth.

    Raises
    ------
    SceneError
        The scene has no usable ``eol`` section.
    """
    station = station_scene(scene)
    pose = None if load is None else body_pose(scene, load)
    cam = car_camera(scene, deviation, load)
    return PoseRenderer(station, cam, pose).frame(cam, progress=progress)
