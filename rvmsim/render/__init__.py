"""Rendering: the scene's meshes as a cube at the camera (:mod:`.cube`, :mod:`.gl`), folded
into the fisheye image (:mod:`.fold`, :func:`render_fisheye`); cached on disk (:mod:`.cache`)."""

from __future__ import annotations

from .cube import CubeLayout, FaceCrop, cube_layout, face_coords, face_rotation, FACE_NAMES, GUARD_PX
from .gl import FaceAtlas, render_faces
from .fold import fold
from .fisheye import FisheyeImages, render_fisheye
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
    "FaceAtlas",
    "cube_layout",
    "face_coords",
    "face_rotation",
    "render_faces",
    "fold",
    "render_fisheye",
    "FACE_NAMES",
    "GUARD_PX",
    "cache_dir",
    "scene_key",
    "file_scene_key",
    "same_scene",
    "cached_render",
    "RENDER_VERSION",
]
