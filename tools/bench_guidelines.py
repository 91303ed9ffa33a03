"""Benchmark: the parking guidelines of every bundled vehicle's tuned setting against the
lines painted on its rendered ground (the renderer check), and the time of
``rvmsim guidelines`` with 109 steering angles (not a test).

    python tools/bench_guidelines.py [--vehicles abcdef] [--runs DIR] [--repeat 3]

For each vehicle: ``rvmsim tune scenes/vehicle_X.yaml`` on defaults into ``--runs`` (skipped
when ``DIR/vehicle_X/top/rank_1.yaml`` exists), then the check at the RVM image of record
(1280 × 720) on a full-size render: G-1 (marks and width lines) and G-2 (trajectories at 0,
±50 %, ±100 % of the steering range), the largest line offset in px and its cm on the ground.
Then ``rvmsim guidelines scenes/vehicle_a.yaml --steering -540:540:10`` as a user runs it
(a new interpreter, warm render cache), ``--repeat`` times, wall seconds each.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

from rvmsim.guidelines.check import STATIC_KINDS, TRAJECTORY_KINDS, check_guidelines
from rvmsim.isp import load_params
from rvmsim.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent


def _tuned(letter: str, runs: Path) -> Path:
    best = runs / f"vehicle_{letter}" / "top" / "rank_1.yaml"
    if not best.is_file():
        subprocess.run([sys.executable, "-m", "rvmsim", "tune", ROOT / "scenes" /
                        f"vehicle_{letter}.yaml", "--out", runs / f"vehicle_{letter}", "--force",
                        "--no-progress"], check=True, stdout=subprocess.DEVNULL)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vehicles", default="abcdef")
    ap.add_argument("--runs", type=Path, default=None, help="tuning runs (default: temporary)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"load {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        runs = args.runs or Path(tmp)
        print("| vehicle | G-1 px (cm) | G-2 px (cm) | lines measured | check s |")
        print("|---|---|---|---|---|")
        for letter in args.vehicles:
            best = _tuned(letter, runs)
            scene = load_scene(ROOT / "scenes" / f"vehicle_{letter}.yaml")
            params, output = load_params(best)
            t = time.perf_counter()
            res = check_guidelines(scene, params, output)
            dt = time.perf_counter() - t
            figures = []
            for kinds in (STATIC_KINDS, TRAJECTORY_KINDS):
                lines = [c for c in res.lines if c.kind in kinds and c.measured]
                worst = max(lines, key=lambda c: c.offset_px)
                figures.append(f"{worst.offset_px:.2f} ({max(c.offset_cm for c in lines):.2f})")
            measured = sum(c.measured for c in res.lines)
            print(f"| {letter.upper()} | {figures[0]} | {figures[1]} | {measured} of "
                  f"{len(res.lines)} | {dt:.1f} |", flush=True)
        times = []
        for _ in range(args.repeat):
            t = time.perf_counter()
            subprocess.run([sys.executable, "-m", "rvmsim", "guidelines",
                            ROOT / "scenes" / "vehicle_a.yaml", "--out", Path(tmp) / "lines",
                            "--steering", "-540:540:10", "--no-progress"], check=True,
                           stdout=subprocess.DEVNULL)
            times.append(time.perf_counter() - t)
        print("rvmsim guidelines vehicle A, 109 angles, warm cache: "
              + ", ".join(f"{x:.2f} s" for x in times))


if __name__ == "__main__":
    main()
