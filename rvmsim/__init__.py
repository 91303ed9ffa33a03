"""rvmsim: tune a rear-view-monitoring camera's ISP from the vehicle's design data.

Pipeline: scene (YAML) → meshes → fisheye images (rendered once) → ISP → evaluation → tuning.

Public API::

    from rvmsim import load_scene, render_fisheye
    scene = load_scene("scenes/vehicle_a.yaml")
    images = render_fisheye(scene)          # images.color (H, W, 3) uint8, images.labels (H, W)
"""

from __future__ import annotations

from .camera import FisheyeCamera, rotation_from_ypr
from .errors import RvmsimError, SceneError
from .scene import Scene, load_scene, scene_from_dict

__all__ = [
    "FisheyeCamera",
    "rotation_from_ypr",
    "RvmsimError",
    "SceneError",
    "Scene",
    "load_scene",
    "scene_from_dict",
    "render_fisheye",
    "FisheyeImages",
]

__version__ = "0.1.0"


def __getattr__(name: str):  # lazy: importing rvmsim must not start OpenGL
    if name in ("render_fisheye", "FisheyeImages"):
        from .render import fisheye

        return getattr(fisheye, name)
    raise AttributeError(f"module 'rvmsim' has no attribute {name!r}")
