"""Benchmark: tuning throughput and the paper protocol's wall time (not a test).

    python tools/bench_tune.py [scenes/vehicle_a.yaml] [--trials 20000] [--workers 2]
        [--size W H]

Runs the paper's grid-to-random protocol (3⁹ = 19,683 coarse candidates, then N = 2 seeds ×
T fine candidates) on the scene with ``--workers`` processes, from a warm render cache, and
prints evaluations/s and the wall time; as the baseline in the same run, the search
throughput of one process over the first ~10 s of the same protocol.  Runs go to a temporary
folder.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

from rvmsim.tune import RunOptions, TuneRequest, tune
from rvmsim.search import TuningConfig


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--trials", type=int, default=20000)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--size", type=int, nargs=2, metavar=("W", "H"),
                    help="the search size (default: the RVM image of record, 1280x720)")
    args = ap.parse_args()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        cfg = TuningConfig.model_validate({"output": {"size": args.size}} if args.size else {})
        # Warm the render cache (rendering is once per scene, not part of the protocol).
        tune(TuneRequest((args.scene,), "random", cfg, budget=1), tmp / "warm")
        one = tune(TuneRequest((args.scene,), "grid-random", cfg, budget=args.trials),
                   tmp / "one", options=RunOptions(max_time=10.0))  # ~10 s of searching
        base_rate = one.outcome.evaluated / one.outcome.seconds
        t = time.perf_counter()
        run = tune(TuneRequest((args.scene,), "grid-random", cfg, budget=args.trials),
                   tmp / "full", options=RunOptions(args.workers))
        wall = time.perf_counter() - t
        n = run.outcome.evaluated
        print(f"scene {args.scene}: paper protocol, {n} evaluations "
              f"(3^9 coarse + 2 x {args.trials} fine), RVM {cfg.output_spec().width}x{cfg.output_spec().height}")
        print(f"  {args.workers} workers: {wall:.1f} s wall, {n / wall:.0f} evaluations/s "
              f"(search only: {run.outcome.seconds:.1f} s)")
        print(f"  baseline, 1 process, first {one.outcome.evaluated} candidates: {base_rate:.0f} "
              f"evaluations/s -> {n / run.outcome.seconds / base_rate:.2f}x with "
              f"{args.workers} workers")
        print(f"  best EC score {run.outcome.best.score:.4g}")
        # Storage: what the main process does per batch, i.e. write the run's already
        # serialised trials again, a batch (1024, the default) per transaction.
        import sqlite3

        from rvmsim.runs import RunStore

        src = sqlite3.connect(tmp / "full" / "run.sqlite")
        rows = src.execute("SELECT idx, stage, params, score, objective, passed, ec FROM trials"
                           " ORDER BY idx").fetchall()
        src.close()
        dst = RunStore(tmp / "copy.sqlite")
        t = time.perf_counter()
        for i in range(0, len(rows), 1024):
            dst.add_rows(rows[i : i + 1024])
        store_s = time.perf_counter() - t
        dst.close()
        print(f"  storage: {store_s:.2f} s for {len(rows)} trials "
              f"({store_s / run.outcome.seconds:.1%} of the search time)")


if __name__ == "__main__":
    main()
