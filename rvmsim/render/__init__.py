"""Rendering: the scene's meshes as a cube at the camera, folded into the fisheye image; cached."""

from __future__ import annotations

from .fisheye import (
    FisheyeImages,
    CubeLayout,
    FaceCrop,
    cube_layout,
    render_fisheye,
    FACE_NAMES,
)
from .cache import (
    cache_dir,
    scene_key,
    file_scene_key,
    same_scene,
    cached_render,
    RENDER_VERSION,
)

__all__ = [
    "FisheyeImages",
    "CubeLayout",
    "FaceCrop",
    "cube_layout",
    "render_fisheye",
    "FACE_NAMES",
    "cache_dir",
    "scene_key",
    "file_scene_key",
    "same_scene",
    "cached_render",
    "RENDER_VERSION",
]
