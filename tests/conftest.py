"""Shared fixtures: bundled scenes and small real renders (pyrender through EGL)."""

from __future__ import annotations

import functools
import os
from pathlib import Path

import pytest

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"

#: Test folders whose files share fixtures of package or session scope (a sweep run and a
#: Dask cluster, rendered board views, a tuning run and a browser): under pytest-xdist
#: (``--dist loadgroup``) each of them runs on one worker, so those fixtures are made once;
#: every other test file is a group of its own.
SHARED_FIXTURE_FOLDERS = ("batch", "calibrate", "console")

if os.environ.get("PYTEST_XDIST_WORKER") and "RVMSIM_CACHE" not in os.environ:
    # A render cache per worker: the cache writes its PNGs in place, so a worker reading an
    # entry another is writing would find it damaged (a warning, an error under pytest).
    os.environ["RVMSIM_CACHE"] = str(Path.home() / ".cache" / "rvmsim" /
                                     f"render-{os.environ['PYTEST_XDIST_WORKER']}")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Under pytest-xdist: each item's group (:data:`SHARED_FIXTURE_FOLDERS`, else its
    file), for ``--dist loadgroup``."""
    if not config.pluginmanager.hasplugin("xdist"):
        return
    tests = Path(__file__).resolve().parent
    for item in items:
        rel = Path(item.path).resolve().relative_to(tests)
        group = rel.parts[0] if rel.parts[0] in SHARED_FIXTURE_FOLDERS else rel.as_posix()
        item.add_marker(pytest.mark.xdist_group(group))


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
