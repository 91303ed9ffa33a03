"""Shared fixtures: bundled scenes and small real renders (pyrender through EGL)."""

from __future__ import annotations

import functools
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from rvmsim._procs import start_worker_server
from rvmsim.camera import rotation_from_ypr
from rvmsim.render import RenderProcess, cached_render, render_fisheye
from rvmsim.testing.captures import BAIC
from rvmsim.testing.scenes import load_small_scene

from .cli_runner import FORK_SERVER_PRELOAD

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
if os.environ.get("PYTEST_XDIST_WORKER"):
    # pytest-xdist already runs one test process per core: one thread per library in each
    # (OpenCV, OpenBLAS/OpenMP, Mesa's llvmpipe; inherited by the commands tests start), so
    # the workers do not contend for the cores (tests/tune, robust, criteria and pipeline on
    # 2 cores: 152 s and 158 s without, 138 s and 132 s with).
    for _var in ("OPENCV_FOR_THREADS_NUM", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                 "LP_NUM_THREADS"):
        os.environ.setdefault(_var, "1")

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "scenes"


def pytest_configure(config: pytest.Config) -> None:
    """In a process that runs tests (not pytest-xdist's controller): start the worker fork
    server now, so that it imports the package for the pools' and renders' workers, and
    the command line for the commands the tests run in forked children
    (:data:`tests.cli_runner.FORK_SERVER_PRELOAD`), while this process collects the tests
    (as ``rvmsim.cli.entry`` does for a command).  One server serves both: whichever started
    it first would leave the other's modules to every child to import again."""
    if os.environ.get("PYTEST_XDIST_WORKER") or not getattr(config.option, "numprocesses",
                                                            None):
        start_worker_server(also=FORK_SERVER_PRELOAD)

#: Tests of the real BAIC EU5 capture run where it is (``rvmsim.testing.captures.BAIC``).
needs_real = pytest.mark.skipif(not BAIC.is_file(),
                                reason=f"real capture not found at {BAIC} "
                                       "(set RVMSIM_REAL_CAPTURES)")

#: Test folders whose files share fixtures of package or session scope (a sweep run and a
#: Dask cluster, rendered board views, a tuning run and a browser): under pytest-xdist
#: (``--dist loadgroup``) each of them runs on one worker, so those fixtures are made once;
#: every other test file is a group of its own.
SHARED_FIXTURE_FOLDERS = ("batch", "calibrate", "console")


@pytest.fixture(scope="session", autouse=True)
def session_render_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One render cache per test session, under its temporary folder and never the user's
    (issue #42): the suite's time and results do not depend on what an earlier run or the
    user left in ``~/.cache/rvmsim``.  Under pytest-xdist the workers share it (the parent
    of their temporary folders): a scene one renders, the others read.  Tests that need a
    cache of their own still set ``RVMSIM_CACHE`` themselves."""
    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    cache = root / "render-cache"
    os.environ["RVMSIM_CACHE"] = str(cache)
    return cache


@pytest.fixture(autouse=True)
def render_worker() -> Iterator[None]:
    """Each test's renders in one render worker (:class:`~rvmsim.render.RenderProcess`),
    as a command's are (``rvmsim.cli.main``): a test that renders several views starts the
    worker once (about 0.12 s a render), and nothing of it is left after the test."""
    with RenderProcess():
        yield


@pytest.hookimpl(tryfirst=True)  # before xdist's own hook, which reads the groups
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
def small_render(letter: str, cube_yaw_deg: float = 0.0):
    """Bundled vehicle ``letter`` at the test scale (:data:`~rvmsim.testing.scenes.QUARTER`
    of its sensor, :func:`~rvmsim.testing.scenes.load_small_scene`, the scene every other
    test builds too), rendered: cached per session, and in the render cache, which every
    test process shares (its entries are written whole, see ``rvmsim._io.write_png``).
    ``cube_yaw_deg`` turns the render's cube (not cached on disk)."""
    scene = load_small_scene(letter)
    if cube_yaw_deg == 0.0:
        return cached_render(scene)[0]
    rot = rotation_from_ypr(cube_yaw_deg, 20.0, 45.0)
    return render_fisheye(scene, cube_rotation=np.asarray(rot))


@functools.lru_cache(maxsize=None)
def sensor_render(letter: str):
    """Bundled vehicle ``letter`` on its own sensor, the product's input, rendered (cached as
    :func:`small_render`).  Not a second test scale: for the checks whose tolerance is a
    claim about the product at its real resolution (projection to 1 px, a solver exact to
    a pixel, a verdict at the display of record), which the test scale's 320 × 240 px
    fisheye cannot resolve."""
    return cached_render(bundled_scene(letter))[0]


@pytest.fixture
def scenes_dir() -> Path:
    return SCENES
