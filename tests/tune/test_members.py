"""Multi-member evaluation: aggregates, the worst-EC column, the combined sub-solves, and
search_members against search_scene (real small renders, real search loops)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rvmsim.criteria import default_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.errors import RvmsimError
from rvmsim.isp import OutputSpec
from rvmsim.pipeline import make_evaluator
from rvmsim.tune import (Aggregate, EcSolver, Member, MembersScorer, MembersSolver, SearchOptions,
                         SearchSettings, check_members, parse_aggregate, score_params,
                         score_vectors, search_members, search_scene, worst_ec_json)
from rvmsim.search import TuningConfig, make_strategy
from rvmsim.render import cached_render
from rvmsim.runs import RunStore, ec_json
from rvmsim.testing.scenes import QUARTER, load_small_scene

from ..conftest import small_render

CFG = TuningConfig.model_validate({"output": {"size": [160, 90]}, "batch": 20})


def test_parse_aggregate_reads_min_and_quantiles_and_refuses_the_rest():
    assert parse_aggregate("min") == Aggregate()
    for text in ("quantile 0.1", "quantile=0.1", "q0.1", "QUANTILE 0.1"):
        assert parse_aggregate(text) == Aggregate("quantile", 0.1)
    assert parse_aggregate("quantile 0.25").text == "quantile 0.25"
    for bad in ("max", "quantile 1", "quantile 0", "q", "quantile x", "quantile -0.2"):
        with pytest.raises(RvmsimError, match="--aggregate"):
            parse_aggregate(bad)


def test_aggregates_reduce_over_members():
    v = np.array([[0.9, 0.1], [0.5, 0.7], [0.2, 0.8], [0.6, 0.4]])  # 4 members, 2 candidates
    assert Aggregate().reduce(v).tolist() == [0.2, 0.1]
    # the lower member value at the quantile: a real member's score
    assert Aggregate("quantile", 0.4).reduce(v).tolist() == [0.5, 0.4]


def test_the_ec_column_holds_each_ecs_worst_member():
    a = ec_json(["1-1", "2-1"], [1.0, 5.0], [1.0, 0.9], [True, True])
    b = ec_json(["1-1", "2-1"], [float("nan"), 9.0], [0.0, 0.2], [False, False])
    c = ec_json(["1-1", "2-1"], [1.0, 3.0], [1.0, 0.3], [True, True])
    doc = json.loads(worst_ec_json([a, b, c]))
    assert doc == {"1-1": [None, 0.0, False], "2-1": [9.0, 0.2, False]}
    assert json.loads(worst_ec_json([a, c])) == {"1-1": [1.0, 1.0, True],
                                                  "2-1": [3.0, 0.3, True]}


@pytest.fixture(scope="module")
def two():
    """Vehicles A and E at the test scale: their evaluators and a space on A's camera."""
    out = OutputSpec(160, 90)
    imgs = [small_render("a"), small_render("e")]
    evs = [CandidateEvaluator(i.labels, out, default_criteria()) for i in imgs]
    return imgs, evs, CFG.space(imgs[0].camera)


def test_members_scorer_combines_the_members_own_verdicts(two):
    imgs, evs, space = two
    rng = np.random.default_rng(3)
    xs = [space.low + rng.random(len(space.names)) * (space.high - space.low) for _ in range(12)]
    b = MembersScorer(evs, space, objective="pass-first")(xs)
    own = [score_vectors(ev, space, xs, objective="pass-first") for ev in evs]
    per = [score_params(ev, [space.params(x) for x in xs]) for ev in evs]
    for i in range(len(xs)):
        scores = [o.score[i] for o in own]
        assert b.score[i] == min(scores)
        assert b.passed[i] == all(o.passed[i] for o in own)
        # members stored in order, each with its own objective
        assert [m[0] for m in b.members[i]] == scores
        assert [m[1] for m in b.members[i]] == pytest.approx([o.objective[i] for o in own])
        # the objective: min log-score, minus the violations of every member
        log = min(p.log_score[i] for p in per)
        assert b.objective[i] == pytest.approx(log - 10.0 * sum(p.violation[i] for p in per))
    one = MembersScorer(evs[:1], space, objective="pass-first")(xs)
    assert one.score == own[0].score


def test_the_combined_solve_is_the_mean_of_the_members_solves(two):
    imgs, evs, space = two
    out = OutputSpec(160, 90)
    solvers = [EcSolver(i.labels, out, default_criteria(), space) for i in imgs]
    p = space.params((space.low + space.high) / 2)
    mean = MembersSolver(solvers, "mean")(p)
    first = MembersSolver(solvers, "first")(p)
    own = [s(p) for s in solvers]
    for n in solvers[0].names:
        assert getattr(first, n) == getattr(own[0], n)
        assert getattr(mean, n) == pytest.approx((getattr(own[0], n) + getattr(own[1], n)) / 2)
    assert getattr(own[0], "adv_h_scale") != getattr(own[1], "adv_h_scale")
    with pytest.raises(ValueError, match="solve mode"):
        MembersSolver(solvers, "median")


def test_one_member_searches_exactly_as_one_scene(two):
    imgs, _, _ = two
    crit = default_criteria()
    a = RunStore(":memory:")
    b = RunStore(":memory:")
    how = SearchSettings(CFG, crit, "cmaes-solved", budget=120)
    search_scene(imgs[0], how, a)
    search_members([Member("A", imgs[0].labels, imgs[0].camera)], how, b)
    assert [(r.params, r.score, r.objective, r.ecs) for r in a.trials()] == \
        [(r.params, r.score, r.objective, r.ecs) for r in b.trials()]
    assert b.member_results(0) == []  # no members table for one member


def test_two_members_store_each_members_results(two, tmp_path):
    imgs, evs, _ = two
    crit = default_criteria()
    store = RunStore(tmp_path / "run.sqlite")
    members = [Member(n, i.labels, i.camera) for n, i in zip("AE", imgs)]
    how = SearchSettings(CFG, crit, "cmaes-solved", budget=60)
    out = search_members(members, how, store, options=SearchOptions(workers=2))
    assert out.evaluated >= 60
    best = out.best
    rows = store.member_results(best.idx)
    assert len(rows) == 2
    # each member's stored verdict is what its own evaluator says of the stored parameters,
    # judged at the RVM image of record (the search measured at 160 × 90)
    judged = [make_evaluator(i, CFG.output_spec(), crit) for i in imgs]
    for (score, _, passed, ecs), ev in zip(rows, judged):
        again = score_params(ev, [best.params])
        assert score == pytest.approx(again.score[0])
        assert passed == bool(again.passed[0])
    assert best.score == min(r[0] for r in rows)
    assert best.passed == all(r[2] for r in rows)
    store.close()
    # a worker-process search and an in-process one agree
    again = RunStore(":memory:")
    search_members(members, how, again)
    assert [r.score for r in again.trials()] == [r.score for r in RunStore(
        tmp_path / "run.sqlite", readonly=True).trials()]


def test_members_of_different_sensor_sizes_are_refused(two):
    imgs, _, _ = two
    half = cached_render(load_small_scene("a", QUARTER / 2))[0]
    with pytest.raises(RvmsimError, match="one sensor size"):
        check_members([Member("A", imgs[0].labels, imgs[0].camera),
                       Member("A small", half.labels, half.camera)])
    strat = make_strategy("random", CFG.space(imgs[0].camera), CFG, 0, 10)
    with pytest.raises(RvmsimError, match="A small"):
        search_members([Member("A", imgs[0].labels, imgs[0].camera),
                        Member("A small", half.labels, half.camera)],
                       SearchSettings(CFG, default_criteria(), strat), RunStore(":memory:"))


def test_a_quantile_aggregate_takes_that_quantile_of_scores_and_objectives(two):
    imgs, evs, space = two
    rng = np.random.default_rng(5)
    xs = [space.low + rng.random(len(space.names)) * (space.high - space.low) for _ in range(8)]
    three = [evs[0], evs[1], evs[0]]
    agg = parse_aggregate("quantile 0.5")
    b = MembersScorer(three, space, objective="pass-first", aggregate=agg)(xs)
    for i in range(len(xs)):
        scores = sorted(m[0] for m in b.members[i])
        objectives = sorted(m[1] for m in b.members[i])
        assert b.score[i] == scores[1]  # the middle one of three
        assert b.objective[i] == objectives[1]
        assert b.passed[i] == all(m[2] for m in b.members[i])
    with pytest.raises(ValueError, match="combine"):
        MembersScorer(three, space, combine="mean")
