"""The diverse top-M (rvmsim.runs.diverse) on synthetic record sets: the rule's guarantees
(minimum distance, pools, rank 1, fewer when the space holds no more, determinism) recomputed
independently, and the ``differs`` line."""

from __future__ import annotations

import itertools
import math
import re

import numpy as np
import pytest

from rvmsim.criteria import default_criteria
from rvmsim.isp import IspParams
from rvmsim.search import ParamRange, SearchSpace
from rvmsim.runs import POOLS, EcOutcome, TrialRecord, differs_text, select_diverse

SPACE = SearchSpace((ParamRange("fov", 180.0, 150.0, 210.0, 20.0),
                     ParamRange("zoom", 0.7, 0.25, 1.45, 0.3),
                     ParamRange("adv_v_shift", 0.0, -0.8, 0.8, 0.4)))
CRIT = default_criteria()
#: A passing value of every EC of the default criteria (inside each range).
GOOD = {"1-1": 1.0, "1-2": 20.0, "1-3": 30.0, "1-4": 1.0, "2-1": 6.0, "2-2": 12.0,
        "2-3": 1.0, "2-4": 1.0, "3-1": 1.0, "3-2": 50.0, "4-1": 1.0}


def _record(idx, x, score, passed=True, objective=None, values=None):
    values = {**GOOD, **(values or {})}
    ecs = {ec: EcOutcome(v, 1.0, bool(passed) or ec != "2-3") for ec, v in values.items()}
    return TrialRecord(idx, "test", SPACE.params(x), score,
                       score if objective is None else objective, bool(passed), ecs)


def _random_records(n, seed=0, pass_rate=0.3):
    rng = np.random.default_rng(seed)
    xs = SPACE.low + rng.random((n, 3)) * (SPACE.high - SPACE.low)
    scores = rng.random(n)
    passed = rng.random(n) < pass_rate
    return [_record(i, x, float(s), bool(p)) for i, (x, s, p) in enumerate(zip(xs, scores, passed))]


def _norm(params):
    """Normalised tuned values, written out here independently of the module."""
    return np.array([(getattr(params, r.name) - r.low) / (r.high - r.low) for r in SPACE.ranges])


def _dist(a, b):
    return float(np.sqrt(((_norm(a) - _norm(b)) ** 2).sum()))


def _best(records):
    return max(records, key=lambda r: (r.score, r.objective, -r.idx))


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("min_distance", [0.05, 0.2, 0.45])
def test_candidates_are_apart_rank1_is_best_and_pools_come_in_order(seed, min_distance):
    records = _random_records(400, seed)
    cands = select_diverse(records, SPACE, CRIT, 10, min_distance, 0.02)
    by_idx = {r.idx: r for r in records}
    best = _best(records)
    assert cands[0].trial == best.idx and cands[0].distance == 0 and cands[0].differs == ""
    assert [c.rank for c in cands] == list(range(1, len(cands) + 1))
    for a, b in itertools.combinations(cands, 2):
        assert _dist(a.params, b.params) >= min_distance
    for c in cands:
        rec = by_idx[c.trial]
        assert c.params == rec.params and c.score == rec.score and c.passed == rec.passed
        assert c.distance == pytest.approx(_dist(c.params, best.params))
        if c.rank > 1:
            assert c.differs
    # the pools: all-pass first; a failing one only once no passer is left that is far enough
    pools = [POOLS.index(c.pool) for c in cands[1:]]
    assert pools == sorted(pools)
    chosen = [c.params for c in cands]
    for k, c in enumerate(cands[1:], start=1):
        assert c.passed == (c.pool == "all-pass")
        if c.pool == "score-tolerance":
            assert 0 < c.score >= best.score * 0.98
        if c.pool != "all-pass":
            before = chosen[:k]
            assert not any(r.passed and all(_dist(r.params, p) >= min_distance for p in before)
                           for r in records)


def test_each_all_pass_pick_is_the_farthest_from_those_before():
    records = _random_records(300, 5, pass_rate=0.6)
    cands = select_diverse(records, SPACE, CRIT, 8, 0.05, 0.02)
    chosen = [cands[0].params]
    for c in cands[1:]:
        assert c.pool == "all-pass"
        nearest = {r.idx: min(_dist(r.params, p) for p in chosen) for r in records if r.passed}
        assert min(_dist(c.params, p) for p in chosen) == pytest.approx(max(nearest.values()))
        chosen.append(c.params)


def test_fewer_than_m_when_the_trials_hold_no_more_points_apart():
    rng = np.random.default_rng(3)
    centres = [np.array([160.0, 0.5, -0.5]), np.array([200.0, 1.3, 0.6])]
    records = [_record(i, centres[i % 2] + rng.normal(0, 0.002, 3), 0.5 + 0.001 * i)
               for i in range(200)]  # two tight clusters, all passing
    cands = select_diverse(records, SPACE, CRIT, 10, 0.1, 0.02)
    assert len(cands) == 2
    assert _dist(cands[0].params, cands[1].params) > 1
    assert len(select_diverse(records, SPACE, CRIT, 1, 0.1, 0.02)) == 1
    assert select_diverse([], SPACE, CRIT, 10, 0.1, 0.02) == []


def test_without_passers_near_best_trials_come_first_then_the_rest_by_score():
    recs = [_record(0, [180, 0.7, 0.0], 0.50, False),
            _record(1, [150, 0.7, 0.0], 0.495, False),   # within 2 % of the best: near
            _record(2, [210, 1.45, 0.8], 0.30, False),   # far, low score
            _record(3, [181, 0.71, 0.0], 0.49, False),   # within 2 %, but too close to #1
            _record(4, [180, 0.25, -0.8], 0.40, False)]
    cands = select_diverse(recs, SPACE, CRIT, 10, 0.05, 0.02)
    assert [c.trial for c in cands] == [0, 1, 4, 2]
    assert [c.pool for c in cands] == ["score-tolerance", "score-tolerance", "by-score",
                                       "by-score"]
    assert all("fails 2-3" in c.differs for c in cands[1:])
    # all scores 0: nothing is near the best; objective order decides (then the earliest)
    zero = [_record(i, [150 + 10 * i, 0.7, 0.0], 0.0, False, objective=-float(i))
            for i in range(4)]
    assert [c.trial for c in select_diverse(zero, SPACE, CRIT, 3, 0.05, 0.02)] == [0, 1, 2]


def test_the_choice_is_deterministic_and_ties_go_to_the_better_score():
    records = _random_records(500, 7)
    first = select_diverse(records, SPACE, CRIT, 10, 0.05, 0.02)
    shuffled = list(records)
    np.random.default_rng(0).shuffle(shuffled)
    assert select_diverse(shuffled, SPACE, CRIT, 10, 0.05, 0.02) == first
    # two candidates equally far from rank 1: the better-scoring one is taken
    recs = [_record(0, [180, 0.7, 0.0], 0.9), _record(1, [150, 0.7, 0.0], 0.2),
            _record(2, [210, 0.7, 0.0], 0.3)]
    assert [c.trial for c in select_diverse(recs, SPACE, CRIT, 2, 0.05, 0.02)] == [0, 2]


def test_thousands_of_trials_are_chosen_from():
    records = _random_records(5000, 11)
    cands = select_diverse(records, SPACE, CRIT, 20, 0.05, 0.02)
    assert len(cands) == 20
    assert min(_dist(a.params, b.params) for a, b in itertools.combinations(cands, 2)) >= 0.05


def test_fixed_and_empty_span_parameters_do_not_count():
    space = SearchSpace(SPACE.ranges + (ParamRange("rad", 600.0, 600.0, 600.0, 1.0),),
                        IspParams(tilt=3.0))
    recs = [TrialRecord(i, "t", space.params([180, z, 0.0, 600]), s, s, True,
                        _record(0, [180, 0.7, 0], 1).ecs)
            for i, (z, s) in enumerate([(0.3, 0.7), (0.31, 0.69), (1.4, 0.1)])]
    cands = select_diverse(recs, space, CRIT, 3, 0.05, 0.02)
    assert [c.trial for c in cands] == [0, 2]
    assert cands[1].distance == pytest.approx(1.1 / 1.2)


# ---------------------------------------------------------------------------- differs
def test_differs_names_the_largest_change_with_rank_1_s_value_and_its_unit():
    first = _record(0, [180, 0.7, 0.0], 0.9)
    fov = _record(1, [168, 0.7, 0.01], 0.8)
    text = differs_text(first, fov, SPACE, CRIT)
    # a smaller FOV with the same RAD reads farther out in the fisheye image: a wider view
    assert text.startswith("wider view: FOV 168° (rank 1: 180°)")
    assert text.index("FOV 168°") < text.index("adv V shift 0.010 (rank 1: 0.000)")
    up = differs_text(first, _record(2, [180.5, 0.95, 0.0], 0.8), SPACE, CRIT)
    assert up.split(": ", 1)[1].startswith("zoom 0.95 (rank 1: 0.70)")
    assert "FOV 180.50° (rank 1: 180.00°)" in up  # the second change, with its unit
    # no signed change anywhere: "wider view" beside "FOV -12°" read as a contradiction
    assert not re.search(r"[A-Za-z] [+-]\d", text + up)


def test_differs_says_wider_or_narrower_from_the_view_itself():
    first = _record(0, [180, 0.7, 0.0], 0.9)
    assert differs_text(first, _record(1, [180, 0.5, 0.0], 0.8), SPACE, CRIT).startswith(
        "wider view: zoom 0.50 (rank 1: 0.70)")
    assert differs_text(first, _record(1, [180, 0.9, 0.0], 0.8), SPACE, CRIT).startswith(
        "narrower view: zoom 0.90 (rank 1: 0.70)")
    # a larger FOV with the same RAD reads nearer the image centre: a narrower view
    assert differs_text(first, _record(1, [200, 0.7, 0.0], 0.8), SPACE, CRIT).startswith(
        "narrower view: FOV 200° (rank 1: 180°)")
    # moving the window down the plane (adv V shift > 0) reads lower rows of the fisheye
    moved = differs_text(first, _record(1, [180, 0.7, 0.3], 0.8), SPACE, CRIT)
    assert moved.startswith("view lower: adv V shift 0.30 (rank 1: 0.00)")
    # a change too small to see gets no word
    assert differs_text(first, _record(1, [180.3, 0.7, 0.0], 0.8), SPACE,
                        CRIT) == "FOV 180.30° (rank 1: 180.00°)"


def test_differs_names_the_ec_margin_that_changes_most():
    first = _record(0, [180, 0.7, 0.0], 0.9, values={"2-1": 6.0, "3-2": 50.0})
    other = _record(1, [170, 0.7, 0.0], 0.8, values={"2-1": 4.5, "3-2": 49.0})
    text = differs_text(first, other, SPACE, CRIT)
    # 2-1: margin 2 -> 0.5 % of a half-width of 2; 3-2: 5 -> 4 of 5 (a smaller change)
    assert text.endswith("; 2-1 bumper center ratio margin lower (2 → 0.5 %)")
    cands = select_diverse([first, other], SPACE, CRIT, 2, 0.05, 0.02)
    assert cands[1].differs == text
    assert cands[1].margins["2-1"] == pytest.approx(0.5)
    assert cands[0].margins["2-1"] == pytest.approx(2.0)
    assert math.isclose(cands[1].margins["3-2"], 4.0)
