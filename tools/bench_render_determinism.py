"""Benchmark: do renders of the same scene agree bit for bit across processes? (not a test)

    python tools/bench_render_determinism.py [--pairs 10] [--jobs 2] [scenes/vehicle_*.yaml …]

For each scene, ``2 × pairs`` fresh ``rvmsim render`` processes (``jobs`` at a time; the
render command never reads the render cache) render the full sensor; each pair's label and
colour PNGs are compared pixel by pixel.  Prints, per scene, the label pixels and the
colour pixels that differ in the worst pair and the largest colour difference (grey
levels), with the machine and the load.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from _bench_common import cpu_model

import imageio.v3 as iio
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def render(scene: Path, out: Path) -> Path:
    subprocess.run([sys.executable, "-m", "rvmsim", "render", str(scene), "--out", str(out),
                    "--no-progress"], check=True, capture_output=True)
    return out


def differences(a: Path, b: Path) -> tuple[int, int, int]:
    """(label pixels, colour pixels, largest colour difference) between two render folders."""
    la, lb = (iio.imread(p / "fisheye_labels.png") for p in (a, b))
    ca, cb = (iio.imread(p / "fisheye_color.png").astype(int) for p in (a, b))
    diff = np.abs(ca - cb)
    return int((la != lb).sum()), int(diff.max(axis=-1).astype(bool).sum()), int(diff.max())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", type=Path,
                    default=sorted((ROOT / "scenes").glob("vehicle_*.yaml")))
    ap.add_argument("--pairs", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {sys.version.split()[0]}; "
          f"load at start {os.getloadavg()[0]:.2f}")
    total_labels = 0
    with tempfile.TemporaryDirectory() as tmp, ThreadPoolExecutor(args.jobs) as pool:
        for scene in args.scenes:
            outs = [Path(tmp) / f"{scene.stem}_{i}" for i in range(2 * args.pairs)]
            list(pool.map(render, [scene] * len(outs), outs))
            pairs = [differences(outs[2 * i], outs[2 * i + 1]) for i in range(args.pairs)]
            worst = max(pairs)
            total_labels += sum(p[0] for p in pairs)
            print(f"{scene.stem}: {args.pairs} process pairs; worst pair: {worst[0]} label px, "
                  f"{worst[1]} colour px (largest difference {worst[2]} grey levels); label "
                  f"px differing over all pairs: {sum(p[0] for p in pairs)}", flush=True)
    print(f"all scenes: {total_labels} differing label pixels")


if __name__ == "__main__":
    main()
