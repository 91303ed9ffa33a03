"""Rendering: the scene's meshes as a cube at the camera (:mod:`.cube`, :mod:`.gl`), folded
into the fisheye image (:mod:`.fold`, :func:`render_fisheye`); cached on disk (:mod:`.cache`)."""

from __future__ import annotations

from .cube import (CubeLayout, FaceCrop, CameraRays, cube_layout, cover_layout, refold_layout,
                   refold_coords,
                   face_coords, face_rotation, FACE_NAMES, GUARD_PX)
from .gl import FaceAtlas, RenderProcess, render_faces
from .fold import fold, fold_color, fold_labels, nearest_labels
from .fisheye import FisheyeImages, render_fisheye
from .viewpoint import (CubeView, TaskRunner, cached_cube, cube_key, cube_task, is_vehicle_label,
                        posed_parts, read_cube, render_cubes)
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
    "CameraRays",
    "cover_layout",
    "refold_layout",
    "refold_coords",
    "nearest_labels",
    "face_coords",
    "face_rotation",
    "render_faces",
    "RenderProcess",
    "fold",
    "fold_color",
    "fold_labels",
    "render_fisheye",
    "FACE_NAMES",
    "GUARD_PX",
    "cache_dir",
    "scene_key",
    "file_scene_key",
    "same_scene",
    "cached_render",
    "RENDER_VERSION",
    "posed_parts",
    "cube_key",
    "cached_cube",
    "read_cube",
    "CubeView",
    "TaskRunner",
    "render_cubes",
    "cube_task",
    "is_vehicle_label",
]
