"""Shared fixtures: bundled scenes and small real renders (pyrender through EGL)."""

from __future__ import annotations

import functools
import os
from pathlib import Path

import pytest

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"


@functools.lru_cache(maxsize=None)
def bundled_scene(letter: str):
    from rvmsim.scene import load_scene

    return load_scene(SCENES / f"vehicle_{letter}.yaml")


@functools.lru_cache(maxsize=None)
def small_render(letter: str, scale: float = 0.5, cube_yaw_deg: float = 0.0):
    """Render bundled vehicle ``letter`` at ``scale`` of its sensor size (cached per session)."""
    import numpy as np

    from rvmsim.camera import rotation_from_ypr
    from rvmsim.render import render_fisheye

    scene = bundled_scene(letter)
    cam = scene.fisheye_camera().scaled(scale)
    rot = None if cube_yaw_deg == 0.0 else rotation_from_ypr(cube_yaw_deg, 20.0, 45.0)
    return render_fisheye(scene, camera=cam, cube_rotation=rot if rot is None else np.asarray(rot))


@pytest.fixture
def scenes_dir() -> Path:
    return SCENES
