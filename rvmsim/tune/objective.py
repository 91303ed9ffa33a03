"""What the search maximises, and the scoring of a batch of candidates for the run store.

The EC score of a candidate is the product of its enabled ECs' sigmoid scores; the
strategies that need a slope (CMA-ES) maximise the objective ``Σ log(max(score_i,
OBJECTIVE_FLOOR))`` over the enabled ECs instead, so that a criterion stuck at ~0 still
leaves something to climb.  Every strategy is told both.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..criteria import CandidateEvaluator, score_batch
from .records import ec_json, params_json
from .space import SearchSpace

__all__ = ["OBJECTIVE_FLOOR", "ScoredBatch", "score_vectors"]

#: Floor of each EC score inside the objective's logarithm.
OBJECTIVE_FLOOR = 1e-4


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


def score_vectors(evaluator: CandidateEvaluator, space: SearchSpace,
                  xs: Sequence[np.ndarray]) -> ScoredBatch:
    """Evaluate candidate vectors of ``space`` with a
    :class:`~rvmsim.criteria.CandidateEvaluator`, scored and serialised for the store
    (EC columns in ``evaluator.criteria.ids`` order)."""
    params = [space.params(x) for x in xs]
    ids = evaluator.criteria.ids
    values = np.array([evaluator.values(p) for p in params]).reshape(len(params), len(ids))
    b = score_batch(values, evaluator.criteria)
    ecs = [ec_json(ids, v, s, o) for v, s, o in zip(b.values.tolist(), b.scores.tolist(),
                                                b.passed.tolist())]
    return ScoredBatch(b.score.tolist(), b.objective(OBJECTIVE_FLOOR).tolist(),
                       b.all_passed.tolist(), [params_json(p) for p in params], ecs)
