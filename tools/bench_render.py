"""Benchmark: render one scene's fisheye colour + label images (not a test).

    python tools/bench_render.py [scenes/vehicle_a.yaml] [--repeats 3]

Prints the machine, the GL renderer, the time per stage (median of the repeats, the first
run in the process included separately since it compiles shaders), and, as a baseline
measured in the same run, one plain pyrender pinhole frame of the same pixel count with
pyrender's own lit shader, so the figures read as a ratio on any machine.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

import numpy as np  # noqa: E402

from rvmsim.render import render_fisheye  # noqa: E402
from rvmsim.scene import load_scene  # noqa: E402


def gl_renderer() -> str:
    import pyrender
    from OpenGL.GL import GL_RENDERER, GL_VERSION, glGetString

    r = pyrender.OffscreenRenderer(8, 8)
    try:
        return f"{glGetString(GL_RENDERER).decode()} / {glGetString(GL_VERSION).decode()}"
    finally:
        r.delete()


def pinhole_baseline(scene, width: int, height: int, repeats: int) -> float:
    """Median seconds for one lit pyrender pinhole frame (pyrender's PBR shader, MSAA)."""
    import pyrender

    from rvmsim.scene import build_parts

    ps = pyrender.Scene(ambient_light=[0.4, 0.4, 0.4])
    for part in build_parts(scene):
        ps.add(pyrender.Mesh.from_trimesh(part.mesh))
    ps.add(pyrender.DirectionalLight(intensity=3.0), pose=np.eye(4))
    cam = scene.fisheye_camera()
    pose = np.eye(4)
    pose[:3, :3] = cam.rotation @ np.diag([1.0, -1.0, -1.0])
    pose[:3, 3] = cam.position
    ps.add(pyrender.IntrinsicsCamera(width / 2, width / 2, width / 2, height / 2), pose=pose)
    r = pyrender.OffscreenRenderer(width, height)
    try:
        r.render(ps)  # shader compile
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            r.render(ps)
            times.append(time.perf_counter() - t)
    finally:
        r.delete()
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    scene = load_scene(args.scene)
    cam = scene.fisheye_camera()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    print(f"GL: {gl_renderer()}")
    print(f"scene: {scene.name}, fisheye {cam.width}x{cam.height} px")
    runs = []
    for i in range(args.repeats + 1):
        t = time.perf_counter()
        img = render_fisheye(scene)
        total = time.perf_counter() - t
        runs.append((total, img.timings))
        tag = "first run (shader compile)" if i == 0 else f"run {i}"
        print(f"  {tag}: {total:.2f} s  " + "  ".join(f"{k} {v:.2f}" for k, v in img.timings.items()))
    steady = [r[0] for r in runs[1:]]
    med = statistics.median(steady)
    print(f"cube: {len(img.faces)} faces {img.faces}, face size {img.face_size} px")
    print(f"fisheye render (colour + labels), median of {len(steady)}: {med:.2f} s")
    base = pinhole_baseline(scene, cam.width, cam.height, args.repeats)
    print(f"baseline, one lit pyrender pinhole frame {cam.width}x{cam.height}: {base:.3f} s")
    print(f"ratio fisheye / pinhole frame: {med / base:.1f}x")


if __name__ == "__main__":
    main()
