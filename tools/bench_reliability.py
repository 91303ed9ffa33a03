"""Benchmark: how reliably each tuning strategy reaches all-pass (not a test).

    python tools/bench_reliability.py [scenes/vehicle_*.yaml] [--seeds 20]
        [--strategies cmaes,reliable] [--budget N] [--workers 2] [--json out.json]

For every scene, strategy and seed 0..N−1 it runs the strategy at its default budget (the
tuning config's defaults, the default criteria, the 640×360 tuning output) on the real
evaluator and records the evaluations to the first candidate that passes every EC.  A run
stops at its first all-pass (what counts is whether, and how soon, the search finds one;
the EC score it goes on to reach is what ``rvmsim tune`` reports).  Printed per scene and
strategy: success rate, median and p90 evaluations to the first all-pass (over the seeds
that reached it), the median wall time per run, the median best EC score, and the best EC
score of the runs that did not pass.  ``--full`` runs every search to its budget instead,
for the EC score the whole run reaches.  Runs are spread over ``--workers`` processes, one evaluation process per run, all
strategies in the same session so that their figures compare.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

_CACHE: dict[str, Any] = {}


def _setup(scene_path: str) -> Any:
    if scene_path not in _CACHE:
        import cv2

        from rvmsim.criteria import default_criteria
        from rvmsim.render import cached_render
        from rvmsim.scene import load_scene
        from rvmsim.tune import candidate_evaluator
        from rvmsim.search import TuningConfig, load_tuning_config

        cv2.setNumThreads(1)
        cfg = (TuningConfig() if not os.environ.get("BENCH_TUNE_CONFIG") else
               load_tuning_config(os.environ["BENCH_TUNE_CONFIG"]))
        images, _ = cached_render(load_scene(scene_path))
        criteria = default_criteria()
        _CACHE[scene_path] = (cfg, images, criteria, candidate_evaluator(images, cfg, criteria))
    return _CACHE[scene_path]


def run_one(scene_path: str, strategy: str, seed: int, budget: int | None,
            full: bool = False) -> dict[str, Any]:
    """One search to its first all-pass (or its budget; with ``full``, always to its
    budget): evaluations used, first all-pass, best EC score."""
    from rvmsim.tune import strategy_scorer
    from rvmsim.search import make_strategy

    cfg, images, criteria, evaluator = _setup(scene_path)
    space = cfg.space(images.camera)
    strat = make_strategy(strategy, space, cfg, seed, budget)
    score = strategy_scorer(strat, evaluator)
    t0 = time.perf_counter()
    gen = strat.batches()
    told = None
    used, first, best = 0, None, 0.0
    try:
        while first is None or full:
            _, xs = gen.send(told) if told is not None else next(gen)
            b = score(xs)
            for k, ok in enumerate(b.passed):
                if ok and first is None:
                    first = used + k + 1
            used += len(xs)
            best = max(best, max(b.score))
            told = list(zip(b.score, b.objective))
    except StopIteration:
        pass
    return {"scene": scene_path, "strategy": strategy, "seed": seed, "first_pass": first,
            "evaluations": used, "best": best, "seconds": time.perf_counter() - t0}


def _pct(values: list[int], q: float) -> float:
    import numpy as np

    return float(np.percentile(values, q)) if values else float("nan")


def summarise(rows: list[dict[str, Any]], scenes: list[str], strategies: list[str],
              seeds: int) -> str:
    import numpy as np

    lines = [f"{'scene':28} {'strategy':13} {'all-pass':>8} {'median':>7} {'p90':>7} "
             f"{'wall/run':>9} {'best':>6}  runs that did not pass (seed: best EC score)"]
    for scene in scenes:
        for strat in strategies:
            rs = [r for r in rows if r["scene"] == scene and r["strategy"] == strat]
            firsts = [r["first_pass"] for r in rs if r["first_pass"] is not None]
            misses = ", ".join(f"{r['seed']}: {r['best']:.2g}" for r in rs
                               if r["first_pass"] is None)
            wall = float(np.median([r["seconds"] for r in rs]))
            best = float(np.median([r["best"] for r in rs]))
            lines.append(f"{Path(scene).stem:28} {strat:13} {len(firsts):>3}/{seeds:<4} "
                         f"{_pct(firsts, 50):7.0f} {_pct(firsts, 90):7.0f} {wall:8.1f}s "
                         f"{best:6.3f}  {misses}")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=sorted(str(p) for p in Path("scenes").glob(
        "vehicle_*.yaml")))
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--strategies", default="cmaes,cmaes-solved")
    ap.add_argument("--budget", type=int, default=None, help="default: each strategy's own")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--full", action="store_true",
                    help="run every search to its budget (and report the EC score reached)")
    ap.add_argument("--config", default=None,
                    help="a tuning config (default: the defaults, as `rvmsim tune`)")
    ap.add_argument("--json", type=Path, default=None, help="also write every run's row here")
    args = ap.parse_args()
    strategies = args.strategies.split(",")
    if args.config:  # read by every process
        os.environ["BENCH_TUNE_CONFIG"] = str(Path(args.config).resolve())
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    for scene in args.scenes:  # warm the render cache before the timed runs
        _setup(scene)
    _CACHE.clear()
    jobs = [(s, st, seed, args.budget, args.full) for s in args.scenes for st in strategies
            for seed in range(args.first_seed, args.first_seed + args.seeds)]
    t0 = time.perf_counter()
    from tqdm import tqdm

    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(run_one, *j) for j in jobs]
        rows = [f.result() for f in tqdm(futures, desc="runs", unit="run")]
    print(f"{len(rows)} runs in {time.perf_counter() - t0:.0f} s on {args.workers} processes")
    print(summarise(rows, args.scenes, strategies, args.seeds))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
