"""Benchmark: the ISP's per-candidate cost (not a test).

    python tools/bench_isp.py [scenes/vehicle_a.yaml] [--candidates 300] [--out 640x480]

Renders the scene once, then for random parameter sets (the nine parameters the paper tunes,
drawn over the ranges a tuning run explores around the paper's defaults) times, on one core
(cv2.setNumThreads(1)): building the map, remapping the label image, remapping the colour
image.  The baseline, measured in the same run, is the map evaluated exactly at every pixel.
The approximation error is the largest distance between the fast and the exact map over
the pixels that read the input image.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map, build_map_exact  # noqa: E402
from rvmsim.render import render_fisheye  # noqa: E402
from rvmsim.scene import load_scene  # noqa: E402

from _bench_common import random_candidates  # noqa: E402



def timed(fn, repeats: int = 1) -> float:
    t = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - t) / repeats


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--candidates", type=int, default=300)
    ap.add_argument("--out", default="640x480")
    args = ap.parse_args()
    w, h = (int(x) for x in args.out.split("x"))
    out = OutputSpec(w, h)
    cv2.setNumThreads(1)
    scene = load_scene(args.scene)
    img = render_fisheye(scene)
    size = (img.camera.width, img.camera.height)
    cands = [IspParams()] + random_candidates(args.candidates - 1)
    t_map, t_lab, t_col, t_exact, errors = [], [], [], [], []
    for i, p in enumerate(cands):
        t_map.append(timed(lambda: build_map(p, size, out), 3))
        m = build_map(p, size, out)
        t_lab.append(timed(lambda: apply_map(img.labels, m), 3))
        if i % 10 == 0:
            t_col.append(timed(lambda: apply_map(img.color, m)))
            t_exact.append(timed(lambda: build_map_exact(p, size, out)))
            ex = build_map_exact(p, size, out)
            inside = (ex.map_x >= -1) & (ex.map_x <= size[0]) & (ex.map_y >= -1) & (ex.map_y <= size[1])
            if inside.any():
                errors.append(float(np.hypot(m.map_x - ex.map_x, m.map_y - ex.map_y)[inside].max()))

    def ms(xs):
        return statistics.median(xs) * 1e3

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"cv2 {cv2.__version__} on 1 thread, numpy {np.__version__}")
    print(f"input {size[0]}x{size[1]} fisheye ({scene.name}), output {w}x{h}, "
          f"{len(cands)} candidates")
    print(f"  build map (fast)          {ms(t_map):7.3f} ms   (p90 {np.percentile(t_map, 90)*1e3:.3f})")
    print(f"  remap labels (nearest)    {ms(t_lab):7.3f} ms")
    print(f"  per candidate in tuning   {ms(t_map) + ms(t_lab):7.3f} ms   (map + labels)")
    print(f"  remap colour (bilinear)   {ms(t_col):7.3f} ms   (only for images people look at)")
    print(f"  baseline: exact map       {ms(t_exact):7.3f} ms   -> fast map is "
          f"{ms(t_exact) / ms(t_map):.0f}x faster")
    print(f"  approximation error       max {max(errors):.4f} px over {len(errors)} checked maps")


if __name__ == "__main__":
    main()
