"""Strategies: the grid-to-random protocol, determinism, CMA-ES against random search on a
real rendered scene, and the registry every strategy is found through."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.tune import (
    STRATEGIES,
    CmaEs,
    GridToRandom,
    RandomSearch,
    SearchSpace,
    Strategy,
    TuningConfig,
    default_space,
    make_strategy,
    register_strategy,
)

from ..conftest import small_render
from .common import search, small_problem


def test_grid_to_random_follows_the_protocol(tmp_path):
    ev, space = small_problem()
    small = SearchSpace(space.ranges[:3], space.base)  # 27 coarse points
    strat = GridToRandom(small, seed=3, top_n=2, trials=40, batch=16)
    out, trials = search(strat, ev, tmp_path, "g")
    assert out.evaluated == 27 + 2 * 40 == len(trials)
    coarse = [t for t in trials if t.stage == "coarse"]
    assert len(coarse) == 27
    ranked = sorted(coarse, key=lambda t: (-t.score, -t.objective, t.idx))
    for n, seed in enumerate(ranked[:2], start=1):
        fine = [t for t in trials if t.stage == f"fine-{n}"]
        assert len(fine) == 40
        lo, hi = small.narrowed(small.vector(seed.params))
        xs = np.array([small.vector(t.params) for t in fine])
        assert np.all(xs >= lo - 1e-9) and np.all(xs <= hi + 1e-9)
        assert np.all(xs.std(axis=0) > 0)  # really random inside the narrowed range


def test_search_is_deterministic(tmp_path):
    ev, space = small_problem()
    a = search(CmaEs(space, seed=5, budget=60), ev, tmp_path, "a")[1]
    b = search(CmaEs(space, seed=5, budget=60), ev, tmp_path, "b")[1]
    c = search(CmaEs(space, seed=6, budget=60), ev, tmp_path, "c")[1]
    assert [(t.params, t.score) for t in a] == [(t.params, t.score) for t in b]
    assert [t.params for t in a] != [t.params for t in c]


def test_cmaes_beats_random_search_on_a_small_budget(tmp_path):
    ev, space = small_problem()
    wins = 0
    for seed in (0, 1):
        cma = search(CmaEs(space, seed=seed, budget=240), ev, tmp_path, f"c{seed}")[0].best
        rnd = search(RandomSearch(space, seed=seed, budget=240), ev, tmp_path, f"r{seed}")[0].best
        wins += (cma.objective, cma.score) > (rnd.objective, rnd.score)
    assert wins == 2


def test_cmaes_explores_first_and_starts_from_the_best_point():
    """The first batch is the uniform exploration (a tenth of the budget); the first CMA-ES
    generation is centred on the best explored point; the budget is kept exactly."""
    space = default_space(small_render("a").camera)
    target = (space.low + space.high) / 2 + 0.3 * (space.high - space.low)

    def objective(x):  # a smooth bowl in the scaled space, best at `target`
        return -float(np.sum(((x - target) / (space.high - space.low)) ** 2))

    strat = CmaEs(space, seed=3, budget=1000, sigma0=0.05)
    gen = strat.batches()
    stage, xs = next(gen)
    assert stage == "explore" and len(xs) == 100
    objs = [objective(x) for x in xs]
    best = xs[int(np.argmax(objs))]
    stage, ys = gen.send([(0.0, o) for o in objs])
    assert stage == "cmaes-1"
    scaled = (np.mean(ys, axis=0) - best) / (space.high - space.low)
    assert np.all(np.abs(scaled) < 0.1)  # σ0 = 0.05 around the best explored point
    used = len(xs)
    while True:
        used += len(ys)
        try:
            stage, ys = gen.send([(0.0, objective(y)) for y in ys])
        except StopIteration:
            break
    assert used >= 1000 and used - 1000 < 20  # stops at the first generation past the budget


class _CentreFirst(Strategy):
    """A user's strategy: the range centres, then the initial values (two batches of one)."""

    name = "centre-first"
    summary = "the centre of every range, then the initial values"

    @classmethod
    def from_settings(cls, space, settings, *, seed, budget, batch):
        return cls(space, seed=seed)

    def total(self):
        return 2

    def batches(self):
        yield "centre", [(self.space.low + self.space.high) / 2]
        yield "init", [np.array([r.init for r in self.space.ranges])]


def test_a_registered_strategy_runs_through_the_registry(tmp_path):
    ev, space = small_problem()
    register_strategy(_CentreFirst)
    try:
        assert STRATEGIES["centre-first"] is _CentreFirst
        with pytest.raises(ValueError, match="taken"):
            register_strategy(_CentreFirst)
        strat = make_strategy("centre-first", space, TuningConfig(), 0)
        out, trials = search(strat, ev, tmp_path, "c")
    finally:
        del STRATEGIES["centre-first"]
    assert [t.stage for t in trials] == ["centre", "init"] and out.evaluated == 2
    np.testing.assert_allclose(space.vector(trials[0].params), (space.low + space.high) / 2)
    assert "centre-first" not in STRATEGIES
