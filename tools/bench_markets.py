"""Benchmark: one setting for several markets (not a test).

    python tools/bench_markets.py [scenes/vehicle_*.yaml] [--markets fmvss111-full,unr158]
        [--seeds 20] [--strategy cmaes-solved] [--workers 2] [--json out.json]
    python tools/bench_markets.py --timing [scenes/vehicle_a.yaml] [--candidates 300]

Reliability (default): for every scene and seed 0..N−1, the search ``rvmsim tune SCENE
--markets …`` runs (its members: the scene at each market's site with that market's
criteria, :func:`rvmsim.tune.members_scorer`; the default tuning config, searched at the
RVM image of record) at the strategy's default budget, stopped at its first candidate that
passes every market (what counts is whether, and how soon, the search finds one).  A run
that finds none gives the ECs no setting can pass, read from the fisheye labels
(:func:`rvmsim.batch.infeasible_ecs`), else the ECs that failed in its best candidate.

Timing (``--timing``): per market member, the render of its site (full sensor, uncached)
and the cost of one candidate (the windowed evaluator on one core, ``--candidates`` random
candidates of the search space), and for the whole markets scorer against the first market
alone.
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


def _setup(scene_path: str, markets: str) -> Any:
    key = f"{scene_path}|{markets}"
    if key not in _CACHE:
        import cv2

        from rvmsim.criteria import record_size
        from rvmsim.markets import market_members, parse_markets
        from rvmsim.scene import load_scene
        from rvmsim.search import TuningConfig
        from rvmsim.tune.markets import render_market_members

        cv2.setNumThreads(1)
        scene = load_scene(scene_path)
        pairs = market_members([scene], parse_markets(markets))
        renders, members = render_market_members(pairs)
        cfg = TuningConfig().at_record(record_size(pairs[0].criteria, scene))
        _CACHE[key] = (cfg, pairs, renders, members)
    return _CACHE[key]


def run_one(scene_path: str, markets: str, strategy: str, seed: int,
            budget: int | None) -> dict[str, Any]:
    """One search to its first all-pass or its budget."""
    import numpy as np

    from rvmsim.tune import SearchSettings, members_scorer
    from rvmsim.search import make_strategy
    from rvmsim.tune.markets import market_infeasible

    cfg, pairs, renders, members = _setup(scene_path, markets)
    strat = make_strategy(strategy, cfg.space(members[0].camera), cfg, seed, budget)
    scorer = members_scorer(members, strat, SearchSettings(cfg, pairs[0].criteria, strat))
    t0 = time.perf_counter()
    gen = strat.batches()
    told = None
    used, first, best, best_ec = 0, None, -1.0, ""
    try:
        while first is None:
            _, xs = gen.send(told) if told is not None else next(gen)
            b = scorer(xs)
            for k, ok in enumerate(b.passed):
                if ok and first is None:
                    first = used + k + 1
            k = int(np.argmax(b.score))
            if b.score[k] > best:
                best, best_ec = float(b.score[k]), b.ec_json[k]
            used += len(xs)
            told = list(zip(b.score, b.objective))
    except StopIteration:
        pass
    why: list[str] = []
    if first is None:
        why = [f"{p.name} {f.reason}" for p, f in market_infeasible(pairs, renders)]
        if not why and best_ec:
            why = [f"fails {ec}" for ec, cell in json.loads(best_ec).items() if not cell[2]]
    return {"scene": scene_path, "seed": seed, "first_pass": first, "evaluations": used,
            "best": best, "seconds": time.perf_counter() - t0, "why": why}


def _pct(values: list[int], q: float) -> float:
    import numpy as np

    return float(np.percentile(values, q)) if values else float("nan")


def summarise(rows: list[dict[str, Any]], scenes: list[str], seeds: int) -> str:
    import numpy as np

    lines = [f"{'scene':12} {'all-pass':>8} {'median':>7} {'p90':>7} {'wall/run':>9}  "
             "runs without a pass: why"]
    for scene in scenes:
        rs = [r for r in rows if r["scene"] == scene]
        firsts = [r["first_pass"] for r in rs if r["first_pass"] is not None]
        misses = sorted({w for r in rs if r["first_pass"] is None for w in r["why"]})
        wall = float(np.median([r["seconds"] for r in rs]))
        lines.append(f"{Path(scene).stem:12} {len(firsts):>3}/{seeds:<4} {_pct(firsts, 50):7.0f} "
                     f"{_pct(firsts, 90):7.0f} {wall:8.1f}s  {'; '.join(misses)[:400]}")
    return "\n".join(lines)


def timing(scene_path: str, markets: str, n: int) -> None:
    """Render once per site, then the cost of one candidate per member and for all."""
    import cv2

    from _bench_common import random_candidates
    from rvmsim.markets import market_members, parse_markets
    from rvmsim.pipeline import make_evaluator
    from rvmsim.render import render_fisheye
    from rvmsim.scene import load_scene

    cv2.setNumThreads(1)
    cfg, pairs, renders, _ = _setup(scene_path, markets)
    out = cfg.output_spec()
    cands = random_candidates(n, seed=1)
    print(f"{'member':24} {'render (s)':>10} {'per candidate (ms)':>19}")
    total, first = 0.0, None
    for p, im in zip(market_members([load_scene(scene_path)], parse_markets(markets)),
                     renders):
        t0 = time.perf_counter()
        render_fisheye(p.scene)
        rendered = time.perf_counter() - t0
        ev = make_evaluator(im, out, p.criteria)
        ev(cands[0])
        t0 = time.perf_counter()
        for c in cands:
            ev(c)
        per = (time.perf_counter() - t0) / n * 1e3
        total += per
        print(f"{p.name:24} {rendered:10.2f} {per:19.2f}")
        first = per if first is None else first
    assert first is not None
    print(f"{'all markets':24} {'':10} {total:19.2f}  ({total / first:.2f}× the first market "
          "alone)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=sorted(str(p) for p in Path("scenes").glob(
        "vehicle_*.yaml")))
    ap.add_argument("--markets", default="fmvss111-full,unr158")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--strategy", default="cmaes-solved")
    ap.add_argument("--budget", type=int, default=None, help="default: the strategy's own")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--timing", action="store_true")
    ap.add_argument("--candidates", type=int, default=300)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    if args.timing:
        for scene in args.scenes:
            print(scene)
            timing(scene, args.markets, args.candidates)
        return
    for scene in args.scenes:  # renders into the cache before the timed runs
        _setup(scene, args.markets)
    _CACHE.clear()
    jobs = [(s, args.markets, args.strategy, seed, args.budget) for s in args.scenes
            for seed in range(args.seeds)]
    from tqdm import tqdm

    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        futures = [pool.submit(run_one, *j) for j in jobs]
        rows = [f.result() for f in tqdm(futures, desc="runs")]
    print(f"markets {args.markets}, {args.strategy}, {len(jobs)} runs in "
          f"{time.perf_counter() - t0:.0f} s")
    print(summarise(rows, args.scenes, args.seeds))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
