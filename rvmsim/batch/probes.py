"""What a design point's task shares between one-criteria points (:mod:`.point`) and
markets points (:mod:`.markets`): the lock that keeps one OpenGL context at a time per
process, the search budget of a (re-checked) task, and the sensitivity probes around a
point's optimum."""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from .payloads import ParamSensitivity, PointTask, SensitivityDoc
from ..tune import score_vectors
from ..search import make_strategy

if TYPE_CHECKING:
    from ..isp import IspParams
    from ..pipeline import ImageEvaluator
    from ..render import FisheyeImages
    from ..search import SearchSpace, TuningConfig

__all__ = ["RENDER_LOCK", "task_budget", "sensitivity", "probe_sensitivity",
           "SENSITIVITY_STEPS"]

#: Parameter offsets (fractions of its search range) the sensitivity is probed at.
SENSITIVITY_STEPS = (-0.1, -0.05, -0.02, 0.02, 0.05, 0.1)

#: Held while a task renders: one OpenGL context at a time per process (a Dask worker with
#: several threads would otherwise open several at once).
RENDER_LOCK = threading.Lock()


def task_budget(task: PointTask, images: FisheyeImages, config: TuningConfig) -> int | None:
    """The budget to search with: the task's, times its ``budget_factor`` (a re-check); a
    budget of None (the strategy's default) is the strategy's planned size times the factor
    (kept None when the strategy does not know its size in advance)."""
    budget, factor = task["budget"], float(task.get("budget_factor", 1.0))
    if factor == 1.0:
        return budget
    if budget is None:
        budget = make_strategy(task["strategy"], config.space(images.camera), config,
                               task["seed"]).total()
        if budget is None:
            return None
    return max(1, int(round(budget * factor)))


def sensitivity(evaluator: ImageEvaluator, space: SearchSpace, best: IspParams
                ) -> SensitivityDoc:
    """EC score with each tuned parameter moved off the optimum by ±2, 5, 10 % of its range
    (others at the optimum).

    Parameters
    ----------
    evaluator : ImageEvaluator
        The point's evaluator (:func:`rvmsim.pipeline.make_evaluator`).
    space : SearchSpace
        The tuned parameters and their ranges.
    best : IspParams
        The optimum.

    Returns
    -------
    dict
        ``optimum`` (the score there), ``steps`` (:data:`SENSITIVITY_STEPS`) and per tuned
        parameter ``scores`` (one per step, None outside the range) and ``drop_5pct``:
        1 − (mean score at ±5 %) / optimum score; 0 if the parameter does not matter there,
        1 if a small change loses everything (None when the optimum scores 0).
    """

    return probe_sensitivity(lambda xs: score_vectors(evaluator, space, xs).score, space,
                             best)


def probe_sensitivity(score: Callable[[list[np.ndarray]], Sequence[float]],
                      space: SearchSpace, best: IspParams) -> SensitivityDoc:
    """:func:`sensitivity` with any scorer: ``score(xs)`` gives the EC scores of the
    candidate vectors ``xs`` (in ``space``'s order), e.g. the markets' minimum of a markets
    point (:class:`rvmsim.tune.MembersScorer`, no sub-solves)."""
    x0 = space.vector(best)
    lo, hi = space.low, space.high
    xs, meta = [x0.copy()], []
    for i, name in enumerate(space.names):
        for f in SENSITIVITY_STEPS:
            x = x0.copy()
            x[i] = x0[i] + f * (hi[i] - lo[i])
            if lo[i] - 1e-12 <= x[i] <= hi[i] + 1e-12:
                xs.append(x)
                meta.append((name, f))
    scores = list(score(xs))
    s0 = scores[0]
    params: dict[str, ParamSensitivity] = {}
    for name in space.names:
        pts = {f: s for (n, f), s in zip(meta, scores[1:]) if n == name}
        at5 = [pts[f] for f in (-0.05, 0.05) if f in pts]
        drop = (1.0 - float(np.mean(at5)) / s0) if (at5 and s0 > 0) else None
        params[name] = {"scores": [pts.get(f) for f in SENSITIVITY_STEPS], "drop_5pct": drop}
    return {"optimum": s0, "steps": list(SENSITIVITY_STEPS), "params": params}
