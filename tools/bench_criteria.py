"""Benchmark: the eleven ECs, and a whole tuning candidate (ISP map + labels + ECs), one core.

    python tools/bench_criteria.py [scenes/vehicle_a.yaml] [--out 640x480] [--candidates 300]

Not a test.  Renders the scene once (full sensor), then times ``criteria.evaluate`` on the RVM
label image of the paper's default parameters, and the full per-candidate work of tuning for
random parameter sets (same ranges as tools/bench_isp.py), with cv2.setNumThreads(1).  The
baseline in the same run is scikit-image's ``regionprops`` over the same label image (what a
straightforward implementation of the measurements would call).
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
from skimage.measure import regionprops  # noqa: E402

from rvmsim.criteria import default_criteria, evaluate  # noqa: E402
from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map  # noqa: E402
from rvmsim.pipeline import make_evaluator  # noqa: E402
from rvmsim.render import render_fisheye  # noqa: E402
from rvmsim.scene import load_scene  # noqa: E402

from _bench_common import random_candidates  # noqa: E402



def per_call(fn, n: int) -> float:
    t = time.perf_counter()
    for _ in range(n):
        fn()
    return (time.perf_counter() - t) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--out", default="640x480")
    ap.add_argument("--candidates", type=int, default=300)
    args = ap.parse_args()
    w, h = (int(x) for x in args.out.split("x"))
    out = OutputSpec(w, h)
    cv2.setNumThreads(1)
    scene = load_scene(args.scene)
    img = render_fisheye(scene)
    size = (img.camera.width, img.camera.height)
    crit = default_criteria()
    labels = apply_map(img.labels, build_map(IspParams(zoom=0.6, adv_v_shift=0.2), size, out))
    t_ec = statistics.median(per_call(lambda: evaluate(labels, crit), 50) for _ in range(10))
    t_rp = statistics.median(per_call(lambda: regionprops(labels), 5) for _ in range(3))
    cands = random_candidates(args.candidates)
    t = time.perf_counter()
    for p in cands:
        evaluate(apply_map(img.labels, build_map(p, size, out)), crit)
    per_cand = (time.perf_counter() - t) / len(cands)
    fast = make_evaluator(img, out, crit)  # the windowed path
    t = time.perf_counter()
    for p in cands:
        fast(p)
    per_fast = (time.perf_counter() - t) / len(cands)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores; cv2 {cv2.__version__} on 1 "
          f"thread; numpy {np.__version__}")
    print(f"{scene.name}: fisheye {size[0]}x{size[1]} -> RVM {w}x{h}")
    print(f"  eleven ECs on one label image      {t_ec * 1e3:7.3f} ms")
    print(f"  baseline: skimage regionprops      {t_rp * 1e3:7.3f} ms  (ECs are "
          f"{t_rp / t_ec:.1f}x faster)")
    print(f"  whole candidate, whole image       {per_cand * 1e3:7.3f} ms  -> "
          f"{1 / per_cand:.0f} candidates/s per core  (build_map + apply_map + evaluate)")
    print(f"  whole candidate, windowed          {per_fast * 1e3:7.3f} ms  -> "
          f"{1 / per_fast:.0f} candidates/s per core  (CandidateEvaluator, same results)")


if __name__ == "__main__":
    main()
