"""Strategies: the grid-to-random protocol, determinism, CMA-ES against random search on a
real rendered scene, and the registry every strategy is found through."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.search import (
    SEED_MAX,
    STRATEGIES,
    CmaEs,
    GridToRandom,
    RandomSearch,
    SearchSpace,
    Strategy,
    TuningConfig,
    check_seed,
    default_space,
    make_strategy,
    register_strategy,
)

from ..conftest import small_render
from ..tune.common import search, small_problem


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


# ---------------------------------------------------------------------------- seeds
def _drive(strategy: Strategy, limit: int = 4000) -> list[tuple[str, np.ndarray]]:
    """Every batch a strategy proposes, told a smooth objective (a bowl in the scaled space
    that CMA-ES converges on, so that it restarts)."""
    space = strategy.space
    centre = (space.low + space.high) / 2

    def objective(x):
        return -float(np.sum(((x - centre) / (space.high - space.low)) ** 2))

    out, gen, told = [], strategy.batches(), None
    while sum(len(xs) for _, xs in out) < limit:
        try:
            stage, xs = gen.send(told) if told is not None else next(gen)
        except StopIteration:
            break
        out.append((stage, np.array(xs)))
        told = [(0.5, objective(x)) for x in xs]
    return out


def _same(a, b) -> bool:
    return len(a) == len(b) and all(sa == sb and np.array_equal(xa, xb)
                                    for (sa, xa), (sb, xb) in zip(a, b))


def test_seeds_up_to_the_top_of_the_range_run_and_repeat():
    """CMA-ES seeds whose seed·1000 overflowed numpy's 32-bit seeds (>= 4,294,968) crashed
    after the exploration; every seed up to SEED_MAX now runs, restarts included, repeats
    itself and differs from its neighbour."""
    space = default_space(small_render("a").camera, ("zoom", "adv_v_shift"))
    for seed in (4_294_968, SEED_MAX):
        runs = [_drive(CmaEs(space, seed=s, budget=3000, sigma0=0.3))
                for s in (seed, seed, seed - 1)]
        assert any(stage == "cmaes-2" for stage, _ in runs[0])  # a restart happened
        assert _same(runs[0], runs[1]) and not _same(runs[0], runs[2])
    for cls in (GridToRandom, RandomSearch):
        assert _same(_drive(cls(space, seed=SEED_MAX), 600), _drive(cls(space, seed=SEED_MAX), 600))


def test_small_seeds_keep_their_cmaes_streams():
    """A restart's seed is still seed·1000 + restart where that fits (every run made before
    the overflow was fixed repeats exactly): the first generation is CMA's with that seed."""
    from cmaes import CMA

    space = default_space(small_render("a").camera, ("zoom", "adv_v_shift"))
    for seed in (0, 7, 4_294_967):
        stage, xs = _drive(CmaEs(space, seed=seed, budget=200, explore=0), 1)[0]
        start = np.array([(r.init - r.low) / (r.high - r.low) for r in space.ranges])
        opt = CMA(mean=start, sigma=0.3, bounds=np.tile([0.0, 1.0], (2, 1)), seed=seed * 1000)
        expected = [space.low + opt.ask() * (space.high - space.low)
                    for _ in range(opt.population_size)]
        assert stage == "cmaes-1" and np.array_equal(xs, np.array(expected))


@pytest.mark.parametrize("seed", [-1, SEED_MAX + 1, 2**64, True, 1.5, "3"])
def test_a_seed_out_of_range_is_refused_naming_the_range(seed):
    space = default_space(small_render("a").camera, ("zoom",))
    for cls in (CmaEs, GridToRandom, RandomSearch):
        with pytest.raises(RvmsimError, match=f"not a seed; give an integer from 0 to {SEED_MAX}"):
            cls(space, seed=seed)
    with pytest.raises(RvmsimError, match="^--seed "):
        check_seed(seed)
    assert check_seed(SEED_MAX) == SEED_MAX and check_seed(np.int64(3)) == 3
