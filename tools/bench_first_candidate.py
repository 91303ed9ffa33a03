"""How long a command takes to its first stored candidate (issue 44; not a test).

    python tools/bench_first_candidate.py [scenes/vehicle_a.yaml] [--repeat 5] [--workers 2]

Starts ``python3 -m rvmsim tune SCENE --workers W`` as a user would (a new interpreter, the
render cache warm: one untimed run first), and watches the run folder's ``run.sqlite``
every 5 ms from outside.  Prints, per run, the seconds from the process's start to the first
stored trial (the first finished batch) and to the command's end, then the medians.  The
first candidate cannot be seen earlier than its batch is stored; the batch size is printed
alongside (``RunOptions``' default).  Runs go to a temporary folder.
"""

from __future__ import annotations

import argparse
import os
import platform
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _bench_common import cpu_model


def _trials(db: Path) -> int:
    if not db.exists():
        return 0
    try:
        with sqlite3.connect(f"file:{db}?mode=ro", uri=True, timeout=0.01) as con:
            return int(con.execute("SELECT COUNT(*) FROM trials").fetchone()[0])
    except sqlite3.Error:  # not created yet, or locked for the moment
        return 0


def one_run(scene: str, workers: int, budget: int, out: Path) -> tuple[float, float, int]:
    """(s to the first stored trial, s to the end, trials stored then)."""
    cmd = [sys.executable, "-m", "rvmsim", "tune", scene, "--out", str(out), "--force",
           "--workers", str(workers), "--budget", str(budget), "--no-progress"]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    first, count = float("nan"), 0
    while proc.poll() is None:
        count = _trials(out / "run.sqlite")
        if count:
            first = time.perf_counter() - t0
            break
        time.sleep(0.005)
    _, err = proc.communicate()
    end = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        sys.exit(f"tune failed ({proc.returncode}): {err.decode(errors='replace')}")
    return first, end, count


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--budget", type=int, default=300)
    args = ap.parse_args()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"load {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        one_run(args.scene, args.workers, args.budget, Path(tmp) / "warm")  # the render cache
        firsts, ends = [], []
        for i in range(args.repeat):
            first, end, count = one_run(args.scene, args.workers, args.budget,
                                        Path(tmp) / f"run{i}")
            firsts.append(first)
            ends.append(end)
            print(f"run {i + 1}: first stored trial {first:.2f} s ({count} trials in the "
                  f"first batch), command {end:.2f} s")
        print(f"median: first {statistics.median(firsts):.2f} s, command "
              f"{statistics.median(ends):.2f} s")


if __name__ == "__main__":
    main()
