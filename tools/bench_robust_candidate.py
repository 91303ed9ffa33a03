"""Benchmark: the cost of one robust tuning candidate against one nominal candidate (not a
test).

    python tools/bench_robust_candidate.py [scenes/vehicle_a.yaml] [--samples 16]
        [--strategy cmaes-solved] [--candidates 96] [--repeats 3]

Builds, in this process, what a tuning worker holds: the nominal scorer (the scene's
evaluator and, for a solving strategy, its sub-solver) and the robust scorer of
``rvmsim tune --robust --samples K`` (the nominal image and K variation samples, aggregate
``quantile 0.1``), on the default tuning config (the RVM image of record) and the default
criteria, from a warm render cache (the sample renders are made first, untimed).  The
candidates are those a short nominal search of the strategy asks for (half) and uniform
draws from its space (half), scored in batches of 32 as a worker scores them.  Prints the
machine, the milliseconds per candidate of each (the best of ``--repeats`` passes) and their
ratio, robust / nominal.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402
from _bench_common import cpu_model  # noqa: E402

from rvmsim.criteria import default_criteria  # noqa: E402
from rvmsim.render import cached_render  # noqa: E402
from rvmsim.robust import draw_samples, sample_images, variation_for  # noqa: E402
from rvmsim.runs import RunStore  # noqa: E402
from rvmsim.scene import load_scene  # noqa: E402
from rvmsim.tune import (Member, SearchSettings, candidate_evaluator, members_scorer,
                         search_scene, solver_for)
from rvmsim.search import TuningConfig, make_strategy
from rvmsim.tune.loop import VectorScorer  # noqa: E402

_BATCH = 32


def _candidates(images, settings: SearchSettings, n: int) -> list[np.ndarray]:
    """``n`` candidate vectors: the first n/2 a short nominal search asks for, then n/2
    uniform draws from the space."""
    store = RunStore(":memory:")
    try:
        out = search_scene(images, SearchSettings(settings.config, settings.criteria,
                                                  settings.strategy, 0, n // 2), store)
        space = out.space
        asked = [space.vector(r.params) for r in store.trials(0, n // 2)]
    finally:
        store.close()
    rng = np.random.default_rng(0)
    drawn = [space.low + rng.random(len(space.low)) * (space.high - space.low)
             for _ in range(n - len(asked))]
    return asked + drawn


def _ms_per_candidate(scorer, xs: list[np.ndarray], repeats: int) -> float:
    """The best of ``repeats`` passes over ``xs`` in batches, ms per candidate."""
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        for a in range(0, len(xs), _BATCH):
            scorer(xs[a:a + _BATCH])
        best = min(best, time.perf_counter() - t)
    return 1e3 * best / len(xs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--strategy", default="cmaes-solved")
    ap.add_argument("--candidates", type=int, default=96)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    load = os.getloadavg()
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    scene = load_scene(args.scene)
    images, _ = cached_render(scene)
    config, criteria = TuningConfig(), default_criteria()
    settings = SearchSettings(config, criteria, args.strategy, 0, aggregate="quantile 0.1")
    samples = draw_samples(variation_for(scene, None), args.samples, 0)
    members = [Member(f"{scene.name} nominal", images.labels, images.camera, scene)]
    members += [Member(f"{scene.name} sample {i + 1}", im.labels, im.camera, scene)
                for i, im in enumerate(sample_images(scene, samples, color=False))]
    out = config.output_spec()
    print(f"scene {args.scene}: {images.camera.width}x{images.camera.height} fisheye, RVM "
          f"{out.width}x{out.height}, strategy {args.strategy}, K = {args.samples}")
    xs = _candidates(images, settings, args.candidates)
    strat = make_strategy(args.strategy, config.space(images.camera), config, 0)
    evaluator = candidate_evaluator(images, config, criteria)
    nominal = VectorScorer(evaluator, strat.space, solver_for(strat, evaluator), strat.objective)
    t = time.perf_counter()
    robust = members_scorer(members, strat, settings)
    setup = time.perf_counter() - t
    t_nom = _ms_per_candidate(nominal, xs, args.repeats)
    t_rob = _ms_per_candidate(robust, xs, args.repeats)
    print(f"  nominal candidate: {t_nom:7.2f} ms")
    print(f"  robust candidate:  {t_rob:7.2f} ms  ({len(members)} members; scorer built in "
          f"{setup:.1f} s)")
    print(f"  robust / nominal:  {t_rob / t_nom:7.2f}x  ({len(xs)} candidates, best of "
          f"{args.repeats})")


if __name__ == "__main__":
    main()
