"""What the search maximises, and the scoring of a batch of candidates for the run store.

The EC score of a candidate is the product of its enabled ECs' sigmoid scores; the
strategies that need a slope (CMA-ES) maximise an objective instead (every strategy is told
both), one of :data:`OBJECTIVES`:

``log-score``
    ``Σ log(max(score_i, OBJECTIVE_FLOOR))`` over the enabled ECs, so that a criterion stuck
    at ~0 still leaves something to climb.
``pass-first``
    ``log-score − PASS_WEIGHT · Σ violation_i``: the violation of an EC is how far its value
    lies outside its acceptable range, in units of its sigmoid's width there (the slope c1
    below the range, c3 above it), capped at :data:`MAX_VIOLATION`, which is also the
    violation of an EC not measured (the object out of the image).  Getting every EC into
    its range therefore comes first, and the EC score only then; outside the range the
    violation keeps a slope where the floored log-score has none.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from ..criteria import Criteria, score_batch
from ..isp import IspParams
from ..pipeline import ImageEvaluator
from ..runs.records import ec_json, params_json
from ..search.space import SearchSpace

__all__ = ["OBJECTIVE_FLOOR", "OBJECTIVES", "PASS_WEIGHT", "MAX_VIOLATION", "ScoredBatch",
           "score_vectors", "violations", "ParamsScores", "score_params", "score_values",
           "check_objective"]

#: Floor of each EC score inside the objective's logarithm.
OBJECTIVE_FLOOR = 1e-4
#: The objectives a strategy can ask for (:attr:`rvmsim.search.Strategy.objective`).
OBJECTIVES = ("log-score", "pass-first")
#: Weight of the summed range violations in the ``pass-first`` objective.
PASS_WEIGHT = 10.0
#: The largest violation one EC counts with (and that of an EC not measured).
MAX_VIOLATION = 20.0


def violations(values: np.ndarray, criteria: Criteria) -> np.ndarray:
    """How far each EC's value lies outside its acceptable range, in sigmoid widths:
    ``c1·(low − x)`` below, ``c3·(x − high)`` above, 0 inside (and for a binary EC), capped
    at :data:`MAX_VIOLATION`, which is also the violation of a value not measured (NaN);
    disabled ECs count 0.

    Parameters
    ----------
    values : (n, k) float
        Measured values in ``criteria.ids`` order.

    Returns
    -------
    (n, k) float64
    """
    x = np.atleast_2d(np.asarray(values, np.float64))
    low, high, binary, _, c1, _, c3, _, enabled = criteria.arrays
    # an open side has no slope to measure in: count one unit per unit of value there
    w_low = np.where(c1 > 0, c1, 1.0)
    w_high = np.where(c3 > 0, c3, 1.0)
    with np.errstate(invalid="ignore", over="ignore"):
        v = np.maximum(w_low * (low - x), 0.0) + np.maximum(w_high * (x - high), 0.0)
    v = np.where(np.isnan(x), MAX_VIOLATION, np.minimum(v, MAX_VIOLATION))
    return np.where(enabled & ~binary, v, 0.0)


@dataclass(frozen=True)
class ScoredBatch:
    """A batch of evaluated candidates, ready to store: what ``evaluate_batch`` returns to
    :func:`rvmsim.tune.run_search`.  Built by :func:`score_vectors` (in worker processes,
    when tuning runs them, so that the main process only stores and steers)."""

    score: list[float]
    objective: list[float]
    passed: list[bool]
    params_json: list[str]
    ec_json: list[str]
    #: per candidate, each member's (score, objective, passed, ec JSON): empty for one scene
    members: list[list[tuple[float, float, bool, str]]] = field(default_factory=list)


def score_vectors(evaluator: ImageEvaluator, space: SearchSpace,
                  xs: Sequence[np.ndarray],
                  solver: Callable[[IspParams], IspParams] | None = None,
                  objective: str = "log-score") -> ScoredBatch:
    """Evaluate candidate vectors of ``space`` with an evaluator
    (:func:`rvmsim.pipeline.make_evaluator`), scored and serialised for the store
    (EC columns in ``evaluator.criteria.ids`` order).  ``solver`` (an
    :class:`~rvmsim.tune.EcSolver`) first sets the parameters it solves; the stored
    parameters are the solved ones.  ``objective`` is one of :data:`OBJECTIVES`."""
    check_objective(objective)
    params = [space.params(x) for x in xs]
    if solver is not None:
        params = [solver(p) for p in params]
    m = score_params(evaluator, params, violation=objective == "pass-first")
    obj = m.log_score if objective == "log-score" else m.log_score - PASS_WEIGHT * m.violation
    return ScoredBatch(m.score.tolist(), obj.tolist(), m.passed.tolist(),
                       [params_json(p) for p in params], m.ec_json)


def check_objective(objective: str) -> None:
    """ValueError for a name not in :data:`OBJECTIVES`."""
    if objective not in OBJECTIVES:
        raise ValueError(f"unknown objective {objective!r} (known: {', '.join(OBJECTIVES)})")


@dataclass(frozen=True)
class ParamsScores:
    """One evaluator's verdicts on a batch of parameter sets (n candidates): EC score,
    log-score objective, summed range violation (:func:`violations`), all-pass, and the
    ``ec`` column of each (:func:`rvmsim.runs.ec_json`)."""

    score: np.ndarray
    log_score: np.ndarray
    violation: np.ndarray
    passed: np.ndarray
    ec_json: list[str]


def score_params(evaluator: ImageEvaluator, params: Sequence[IspParams], *,
                 violation: bool = True) -> ParamsScores:
    """Evaluate parameter sets (already solved) with ``evaluator``: the part of
    :func:`score_vectors` that a multi-member evaluation repeats per member.  Without
    ``violation`` the violations are not computed (zeros)."""
    ids = evaluator.criteria.ids
    values = np.array([evaluator.values(p) for p in params]).reshape(len(params), len(ids))
    return score_values(values, evaluator.criteria, violation=violation)


def score_values(values: np.ndarray, criteria: Criteria, *, violation: bool = True
                 ) -> ParamsScores:
    """:func:`score_params` from the measured values, (n, k) in ``criteria.ids`` order (NaN
    where not measured)."""
    ids = criteria.ids
    values = np.asarray(values, np.float64).reshape(-1, len(ids))
    b = score_batch(values, criteria)
    ecs = [ec_json(ids, v, s, o) for v, s, o in zip(b.values.tolist(), b.scores.tolist(),
                                                b.passed.tolist())]
    return ParamsScores(np.asarray(b.score, np.float64), b.objective(OBJECTIVE_FLOOR),
                        violations(values, criteria).sum(axis=1) if violation
                        else np.zeros(len(values)),
                        np.asarray(b.all_passed, bool), ecs)
