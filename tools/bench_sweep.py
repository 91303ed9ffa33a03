"""Benchmark: a design sweep on local processes vs a Dask LocalCluster (not a test).

    python tools/bench_sweep.py [sweeps/vehicle_a_mount.yaml] [--workers 2]

Runs the sweep three times into temporary folders, all from the same render cache: once to
warm the cache (not timed for the comparison), then on ``--workers`` local processes and on a
Dask LocalCluster with as many single-threaded worker processes on loopback.  It prints the
wall times, their ratio, the mean seconds per point, whether the two tables are
identical, and the local run's seconds per phase (render, tune, yield) summed over the
points.
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

from rvmsim import batch as S  # noqa: E402
from rvmsim.batch import DaskExecutor, LocalExecutor  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sweep", nargs="?", default="sweeps/vehicle_a_mount.yaml")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    import distributed

    spec = S.load_sweep(args.sweep)
    n = len(S.design_points(spec))
    print(f"{platform.python_version()} on {cpu_model()} ({os.cpu_count()} cores, load "
          f"average {os.getloadavg()[0]:.2f}); "
          f"{args.sweep}: {n} design points, {spec.strategy} budget {spec.budget}")
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        S.run_sweep(spec, Path(tmp) / "warm", executor=LocalExecutor(args.workers))
        print(f"warm-up (renders into the cache): {time.perf_counter() - t:.1f} s")
        t = time.perf_counter()
        local = S.run_sweep(spec, Path(tmp) / "local", executor=LocalExecutor(args.workers))
        t_local = time.perf_counter() - t
        with distributed.LocalCluster(n_workers=args.workers, threads_per_worker=1,
                                      processes=True, host="127.0.0.1",
                                      dashboard_address=":0") as cluster, \
                distributed.Client(cluster) as client:
            t = time.perf_counter()
            dask = S.run_sweep(spec, Path(tmp) / "dask", executor=DaskExecutor(client=client))
            t_dask = time.perf_counter() - t
    per = {name: sum(r["seconds"] for r in res.results.values()) / n
           for name, res in (("local", local), ("dask", dask))}
    same = (S.sweep_table(spec, local.points, local.results)
            == S.sweep_table(spec, dask.points, dask.results))
    print(f"local, {args.workers} processes: {t_local:6.1f} s wall, {per['local']:.2f} s per point")
    print(f"Dask LocalCluster, {args.workers} workers: {t_dask:6.1f} s wall, "
          f"{per['dask']:.2f} s per point")
    print(f"Dask / local wall time: {t_dask / t_local:.2f}; tables identical: {same}")
    phases = S.phase_seconds(local.results)
    print("local, seconds per phase over the points' final runs: "
          + ", ".join(f"{k} {v:.1f}" for k, v in phases.items()))


if __name__ == "__main__":
    main()
