"""The reliable search: given starts, the solved CMA-ES (its reduced space, its restarts,
its pass-first objective), determinism and replay with solved parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rvmsim.criteria import default_criteria, score_batch
from rvmsim.tune import MAX_VIOLATION, run_search, solver_for, strategy_scorer, violations
from rvmsim.search import CmaEs, CmaEsSolved, TuningConfig, default_space, make_strategy
from rvmsim.runs import RunStore

from ..conftest import small_render
from .common import small_problem


def _bowl(space, target):
    def objective(x):
        return -float(np.sum(((np.asarray(x) - target) / (space.high - space.low)) ** 2))
    return objective


@pytest.mark.parametrize("cls", [CmaEs, CmaEsSolved])
def test_given_starts_are_evaluated_first_and_the_best_one_is_where_cmaes_begins(cls):
    space = default_space(small_render("a").camera)
    target = (space.low + space.high) / 2 + 0.2 * (space.high - space.low)
    objective = _bowl(space, target)
    near = target + 0.01 * (space.high - space.low)
    far = space.low + 0.1 * (space.high - space.low)
    strat = make_strategy(cls.name, space, TuningConfig(), 1, 600, starts=[far, near])
    gen = strat.batches()
    stage, xs = next(gen)
    assert stage == "starts"
    np.testing.assert_allclose(xs, [far, near])
    stage, xs = gen.send([(0.0, objective(x)) for x in xs])
    assert stage == "explore"
    # every explored point is worse than `near`, so CMA-ES begins there
    stage, ys = gen.send([(0.0, objective(near) - 1.0) for _ in xs])
    assert stage == "cmaes-1"
    scaled = (np.mean(ys, axis=0) - near) / (space.high - space.low)
    assert np.all(np.abs(scaled) < 0.3)


def test_starts_outside_the_ranges_are_clipped_into_them():
    space = default_space(small_render("a").camera)
    strat = make_strategy("cmaes-solved", space, TuningConfig(), 0, 100,
                          starts=[space.high + 5.0])
    np.testing.assert_allclose(strat.starts[0], space.high)


def test_solved_cmaes_searches_only_what_the_solves_leave():
    """Once the solver has set `solved`, the proposed vectors keep the solved parameters at
    their initial values and vary all the others; restarts grow the population (IPOP)."""
    ev, space = small_problem()
    strat = CmaEsSolved(space, seed=0, budget=1500, explore=20, sigma0=0.3)
    solver = solver_for(strat, ev)
    assert solver is not None and set(strat.solved) == {"adv_v_shift", "adv_h_scale"}
    solved = [space.names.index(n) for n in strat.solved]
    free = [i for i in range(len(space.names)) if i not in solved]
    init = np.array([r.init for r in space.ranges])
    gen = strat.batches()
    told = None
    sizes: dict[str, int] = {}
    xs_all = []
    rng = np.random.default_rng(0)
    try:
        while True:
            stage, xs = gen.send(told) if told is not None else next(gen)
            sizes.setdefault(stage, len(xs))
            xs_all += xs
            # a flat objective with noise: CMA-ES stagnates, so restarts come quickly
            told = [(0.0, float(rng.normal())) for _ in xs]
    except StopIteration:
        pass
    arr = np.array(xs_all)
    np.testing.assert_allclose(arr[:, solved], np.broadcast_to(init[solved], (len(arr), 2)))
    assert np.all(arr[:, free].std(axis=0) > 0)
    restarts = sorted((k for k in sizes if k.startswith("cmaes-")),
                      key=lambda s: int(s.split("-")[1]))
    cma = [sizes[k] for k in restarts]
    assert len(cma) >= 3 and all(b >= 2 * a - 1 for a, b in zip(cma, cma[1:]))


def test_the_pass_first_objective_ranks_any_all_pass_candidate_above_a_failing_one():
    """Violations: zero inside every range, growing with the distance outside, the cap for
    an EC not measured; the objective puts a barely passing candidate above a nearly
    passing one that the log-score prefers."""
    crit = default_criteria()
    ids = list(crit.ids)
    good = {"1-1": 1, "1-2": 30, "1-3": 25, "1-4": 0.3, "2-1": 6, "2-2": 12, "2-3": 1,
            "2-4": 1, "3-1": 0.5, "3-2": 50, "4-1": 1.0}
    barely = dict(good, **{"2-1": 4.01, "2-2": 15.99, "4-1": 1.099})
    nearly = dict(good, **{"2-2": 16.3})
    missing = dict(good, **{"3-1": math.nan})
    far = dict(good, **{"3-1": 300.0})
    values = np.array([[d[i] for i in ids] for d in (good, barely, nearly, missing, far)])
    v = violations(values, crit)
    assert np.all(v[:2] == 0) and v[2].sum() > 0
    k = ids.index("2-2")
    assert v[2, k] == pytest.approx(2.69 * 0.3)
    assert v[3, ids.index("3-1")] == MAX_VIOLATION == v[4, ids.index("3-1")]
    b = score_batch(values, crit)
    logscore = b.objective(1e-4)
    assert logscore[2] > logscore[1]  # the product of scores alone prefers `nearly`
    ev, space = small_problem()
    strat = CmaEsSolved(space, seed=0, budget=10)
    assert strat.objective == "pass-first"
    pass_first = logscore - 10.0 * v.sum(axis=1)
    assert pass_first[1] > pass_first[2] and b.all_passed[1] and not b.all_passed[2]


def test_solved_runs_repeat_per_seed_and_replay_from_their_store(tmp_path):
    """Same seed, same trials (solved parameters included); a store cut short replays its
    trials (their proposed parameters match where not solved) and ends as the unbroken run."""
    ev, space = small_problem()

    def run(name, seed, stop_after=None):
        strat = CmaEsSolved(space, seed=seed, budget=300, explore=30)
        store = RunStore(tmp_path / f"{name}.sqlite")
        scorer = strategy_scorer(strat, ev)
        calls = []

        def evaluate(xs):
            if stop_after is not None and len(calls) == stop_after:
                raise KeyboardInterrupt
            calls.append(len(xs))
            return scorer(xs)

        try:
            out = run_search(strat, evaluate, store)
        except KeyboardInterrupt:
            out = None
        trials = [(t.params, t.score) for t in store.trials()]
        store.close()
        return out, trials

    _, a = run("a", 4)
    _, b = run("b", 4)
    _, c = run("c", 5)
    assert a == b and a != c
    assert len({t[0].adv_v_shift for t in a}) > 10  # solved per candidate, not the init
    _, cut = run("d", 4, stop_after=3)
    assert 0 < len(cut) < len(a)
    strat = CmaEsSolved(space, seed=4, budget=300, explore=30)
    store = RunStore(tmp_path / "d.sqlite")
    out = run_search(strat, strategy_scorer(strat, ev), store)
    assert out.replayed == len(cut) and out.evaluated == len(a) - len(cut)
    assert [(t.params, t.score) for t in store.trials()] == a
    store.close()
