"""How many evaluations CMA-ES needs to reach the EC score grid-to-random reaches (not a test).

    python tools/compare_strategies.py RUNS_GRID RUNS_CMAES

Both folders are ``rvmsim batch`` outputs over the same scenes (one run folder per scene).
For each vehicle: grid-to-random's best EC score and evaluations, and the first CMA-ES trial
whose best-so-far reaches that score (or "not reached" within its budget).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rvmsim.runs import RunStore


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("grid", type=Path)
    ap.add_argument("cmaes", type=Path)
    args = ap.parse_args()
    print(f"{'scene':12} {'grid-random best':>16} {'grid evals':>10} {'CMA-ES best':>12} "
          f"{'CMA evals to reach grid':>24}")
    for run in sorted(p for p in args.grid.iterdir() if (p / "run.sqlite").is_file()):
        other = args.cmaes / run.name
        if not (other / "run.sqlite").is_file():
            continue
        g, c = RunStore(run / "run.sqlite"), RunStore(other / "run.sqlite")
        g_best = g.top(1)[0].score
        reach = next((idx + 1 for idx, best, _ in c.best_curve() if best >= g_best), None)
        print(f"{run.name:12} {g_best:16.4g} {g.count():10d} {c.top(1)[0].score:12.4g} "
              f"{'not reached' if reach is None else reach:>24}")
        g.close()
        c.close()


if __name__ == "__main__":
    main()
