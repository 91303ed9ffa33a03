"""The GL stage: real pyrender (EGL) renders of the cube faces in a process of their own,
and the baked lighting."""

from __future__ import annotations

import multiprocessing.forkserver
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import psutil
import pytest

from rvmsim import labels as L
from rvmsim._procs import start_pool
from rvmsim.errors import RvmsimError
from rvmsim.render import RenderProcess, cube_layout, render_faces, render_fisheye
from rvmsim.render.gl import AMBIENT, LIGHTS, _lambert, _linear_to_srgb
from rvmsim.scene import build_parts
from rvmsim.testing.scenes import load_small_scene, write_small_scene

from ..conftest import bundled_scene


def test_faces_render_into_the_atlas_with_the_parts_labels():
    scene = bundled_scene("a")
    cam = scene.fisheye_camera().scaled(0.1)
    layout = cube_layout(cam, face_size=48)
    parts = build_parts(scene)
    atlas = render_faces(parts, layout, cam, sky=scene.render.sky_color)
    assert atlas.color.shape[:2] == atlas.labels.shape == layout.atlas_shape
    present = set(np.unique(atlas.labels).tolist())
    assert present <= {p.label for p in parts} | {0}
    assert {L.GROUND, L.BUMPER, 0} <= present  # ground below, bumper in view, sky above
    assert atlas.gl_setup_s >= 0 and atlas.faces_s > 0
    # Each crop's columns hold its face: the face looking down the image (+y, toward the
    # ground and the car) sees no sky.
    down = [c for c in layout.crops if c.face == 2]
    assert down
    block = atlas.labels[: down[0].height, down[0].atlas_x0: down[0].atlas_x0 + down[0].width]
    assert np.all(block != 0)


def test_srgb_encoding_and_lambert_shading():
    np.testing.assert_allclose(_linear_to_srgb(np.array([0.0, 1.0, 2.0, -1.0])), [0, 1, 1, 0])
    x = np.array([0.0031308 - 1e-9, 0.0031308 + 1e-9])
    a, b = _linear_to_srgb(x)
    assert b == pytest.approx(a, abs=1e-6)  # continuous at the knee
    # A surface facing away from every light gets the ambient term only.
    away = np.array([direction / np.linalg.norm(direction) for direction, _ in LIGHTS[:1]])
    assert _lambert(away)[0] == pytest.approx(AMBIENT + sum(
        i * max(0.0, float(away[0] @ (-d / np.linalg.norm(d)))) for d, i in LIGHTS[1:]))
    up = np.array([[0.0, -1.0, 0.0]])
    assert _lambert(up)[0] > AMBIENT


def _kill_render_workers(count: int, stop: threading.Event, killed: list[int]) -> None:
    """SIGKILL the first ``count`` children of the fork server (the render workers, one per
    attempt): a crash of the GL driver, as far as the caller can tell."""
    server = psutil.Process(multiprocessing.forkserver._forkserver._forkserver_pid)
    seen: set[int] = set()
    while len(killed) < count and not stop.is_set():
        for child in server.children():
            if child.pid not in seen:
                seen.add(child.pid)
                os.kill(child.pid, signal.SIGKILL)
                killed.append(child.pid)
        time.sleep(0.002)


def _render_while_killing(count: int):
    scene = bundled_scene("a")
    cam = scene.fisheye_camera().scaled(0.1)
    layout = cube_layout(cam, face_size=48)
    parts = build_parts(scene)
    start_pool(1).shutdown()  # the fork server runs (the first render would start it)
    stop, killed = threading.Event(), []
    watch = threading.Thread(target=_kill_render_workers, args=(count, stop, killed))
    watch.start()
    try:
        return render_faces(parts, layout, cam, sky=scene.render.sky_color), killed
    finally:
        stop.set()
        watch.join()


def test_a_render_whose_process_dies_is_rendered_again_in_a_fresh_one():
    atlas, killed = _render_while_killing(1)
    assert len(killed) == 1 and not psutil.pid_exists(killed[0])
    scene = bundled_scene("a")
    cam = scene.fisheye_camera().scaled(0.1)
    again = render_faces(build_parts(scene), cube_layout(cam, face_size=48), cam,
                         sky=scene.render.sky_color)
    np.testing.assert_array_equal(atlas.labels, again.labels)
    assert {L.GROUND, L.BUMPER} <= set(np.unique(atlas.labels).tolist())


def test_a_render_that_dies_twice_is_one_error():
    with pytest.raises(RvmsimError, match="render process died 2 times"):
        _render_while_killing(2)


def test_a_render_process_keeps_one_worker_for_its_block_and_ends_it():
    scene = bundled_scene("a")
    cam = scene.fisheye_camera().scaled(0.1)
    layout = cube_layout(cam, face_size=48)
    parts = build_parts(scene)
    start_pool(1).shutdown()  # the fork server runs
    server = psutil.Process(multiprocessing.forkserver._forkserver._forkserver_pid)
    with RenderProcess() as renders:
        first = render_faces(parts, layout, cam, sky=scene.render.sky_color, renders=renders)
        workers = [c.pid for c in server.children()]
        second = render_faces(parts, layout, cam, sky=scene.render.sky_color, color=False,
                              renders=renders)
        assert [c.pid for c in server.children()] == workers and len(workers) == 1
        # a worker that dies in the block is replaced, and the render still comes back
        dead = psutil.Process(workers[0])
        os.kill(dead.pid, signal.SIGKILL)
        dead.wait(5)
        third = render_faces(parts, layout, cam, sky=scene.render.sky_color, renders=renders)
    np.testing.assert_array_equal(first.labels, second.labels)
    np.testing.assert_array_equal(first.labels, third.labels)
    deadline = time.monotonic() + 5
    while server.children() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert server.children() == []  # gone when the block ends


def test_every_render_of_a_block_however_deep_runs_in_its_one_worker():
    scene = load_small_scene("a")
    start_pool(1).shutdown()  # the fork server runs
    server = psutil.Process(multiprocessing.forkserver._forkserver._forkserver_pid)
    with RenderProcess():
        first = render_fisheye(scene)  # no renders=: the block's worker, kept
        after_first = [c.pid for c in server.children()]
        second = render_fisheye(scene, camera=scene.fisheye_camera())
        after_second = [c.pid for c in server.children()]
    assert len(after_first) == 1 and after_second == after_first
    np.testing.assert_array_equal(first.labels, second.labels)
    deadline = time.monotonic() + 5
    while server.children() and time.monotonic() < deadline:
        time.sleep(0.02)
    assert server.children() == []  # gone when the block ends


def test_a_plain_script_without_a_main_guard_renders_once(tmp_path):
    """A user's script that renders, with no ``if __name__ == "__main__"``: the render
    worker and its fork server do not import the script again (it would run again in each,
    and the render process would die), so it prints its lines once and exits 0."""
    scene = write_small_scene(tmp_path, "a")
    script = tmp_path / "plain.py"
    script.write_text("from rvmsim import load_scene, render_fisheye\n"
                      "print('start', flush=True)\n"
                      f"images = render_fisheye(load_scene({str(scene)!r}))\n"
                      "print('rendered', images.labels.shape, flush=True)\n")
    env = {**os.environ, "RVMSIM_CACHE": str(tmp_path / "cache")}
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300, env=env)
    assert res.returncode == 0, res.stderr[-3000:]
    assert [ln.split()[0] for ln in res.stdout.splitlines()] == ["start", "rendered"]
