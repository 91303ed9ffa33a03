"""One design point as a task: render its scene, check what is infeasible without search,
tune the ISP, probe the sensitivity.

:func:`run_point` is a pure function of its task dict (the point's scene document, tuning
config, strategy, budget, seed, criteria text, and for a re-check the parameter sets to
start from and the budget factor), so it runs the same on a local process or a Dask
worker; it writes no files except into the worker's render cache.
"""

from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np

from ..errors import RvmsimError
from .executors import task_malloc

__all__ = ["run_point", "sensitivity", "SENSITIVITY_STEPS"]

#: Parameter offsets (fractions of its search range) the sensitivity is probed at.
SENSITIVITY_STEPS = (-0.1, -0.05, -0.02, 0.02, 0.05, 0.1)

_RENDER_LOCK = threading.Lock()


def run_point(task: dict[str, Any]) -> dict[str, Any]:
    """Render, tune and probe one design point (runs in a worker; no files but the render
    cache).

    ``task`` holds ``scene`` (document), ``config`` (tuning config document), ``label``,
    ``strategy``, ``budget``, ``seed``, ``criteria`` (text or None), ``criteria_source``,
    ``sensitivity``, ``robustness`` (``{"samples", "seed"}`` of the yield, or None: no
    yield); a re-check adds ``starts`` (parameter dicts, name → value, evaluated first),
    ``budget_factor`` (the budget, or the strategy's default size when the budget is None,
    times this), ``beat`` (``[passed, score]`` of the point's best so far: the yield is
    measured only when this run's best ranks above it, as only then can it be the point's
    final best).  A task with ``yield_of`` (a parameter dict) only measures that setting's
    yield: it returns ``{"robustness", "seconds"}``.

    Returns a JSON-ready dict: ``score``, ``passed``, ``ecs`` (id → value, score, passed),
    ``params``, ``tuned``, ``evaluations``, ``budget`` (the budget searched with, None for
    the strategy's default), ``stopped``, ``limiting_ec`` (the failing enabled EC with the
    lowest score, or None), ``infeasible`` (the enabled ECs no ISP setting can pass here, as
    ``{"ec", "reason"}``: :func:`~rvmsim.batch.feasibility.infeasible_ecs`),
    ``sensitivity`` (see :func:`sensitivity`), ``robustness`` (the best setting's yield,
    :func:`~rvmsim.batch.yields.point_yield`; only when the task asks for one, the scene
    has a ``variation`` section and the run beats ``beat``) and ``seconds``; a problem
    with the point is returned as ``{"error": message, "seconds"}``.
    """
    with task_malloc():
        return _run_point(task)


def _run_point(task: dict[str, Any]) -> dict[str, Any]:
    import os

    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from ..render import cached_render
    from ..isp import IspParams
    from ..runs import RunStore
    from ..tune import SearchSettings, candidate_evaluator, search_scene
    from .feasibility import infeasible_ecs
    from .yields import point_yield

    t0 = time.perf_counter()
    try:
        scene, config, criteria = _task_inputs(task)
        if "yield_of" in task:  # a yield only (a result stored before yields existed)
            rob = task["robustness"]
            with _RENDER_LOCK:
                y = point_yield(scene, IspParams(**task["yield_of"]), config.output_spec(),
                                criteria, rob["samples"], rob["seed"])
            return {"robustness": y, "seconds": time.perf_counter() - t0}
        # One render at a time per process: a Dask worker with several threads would
        # otherwise open several OpenGL contexts at once.
        with _RENDER_LOCK:
            images, _ = cached_render(scene)
        infeasible = infeasible_ecs(scene, images.camera, images.labels, criteria)
        evaluator = candidate_evaluator(images, config, criteria)
        budget = _task_budget(task, images, config)
        starts = [IspParams(**p) for p in task.get("starts", ())]
        store = RunStore(":memory:")
        try:
            how = SearchSettings(config, criteria, task["strategy"], task["seed"], budget,
                                 tuple(starts))
            outcome = search_scene(images, how, store, evaluator=evaluator)
            n_eval = store.count()
        finally:
            store.close()
        best, space = outcome.best, outcome.space
        if best is None:
            raise RvmsimError(f"{task['label']}: the search evaluated no candidate")
        result: dict[str, Any] = {
            "score": best.score,
            "passed": bool(best.passed),
            "ecs": {ec: o.as_dict() for ec, o in best.ecs.items()},
            "params": {n: getattr(best.params, n) for n in best.params.names()},
            "tuned": list(space.names),
            "evaluations": n_eval,
            "budget": budget,
            "stopped": outcome.stopped,
            "infeasible": [x.as_dict() for x in infeasible],
        }
        failing = [(v["score"], ec) for ec, v in result["ecs"].items()
                   if not v["passed"] and criteria.items[ec].enabled]
        result["limiting_ec"] = min(failing)[1] if failing else None
        if task.get("sensitivity", True):
            result["sensitivity"] = sensitivity(evaluator, space, best.params)
        rob = task.get("robustness")
        beat = task.get("beat")
        if (rob and rob["samples"] > 0 and scene.variation is not None
                and (beat is None or (result["passed"], result["score"]) > tuple(beat))):
            with _RENDER_LOCK:  # renders the variation's viewpoints
                result["robustness"] = point_yield(scene, best.params, config.output_spec(),
                                                   criteria, rob["samples"], rob["seed"])
        result["seconds"] = time.perf_counter() - t0
        return result
    except RvmsimError as err:
        return {"error": str(err), "seconds": time.perf_counter() - t0}


def _task_inputs(task: dict[str, Any]) -> tuple[Any, Any, Any]:
    """(scene, tuning config, criteria) of a point's task."""
    from ..criteria import criteria_from_text, default_criteria
    from ..scene import scene_from_dict
    from ..tune import TuningConfig

    scene = scene_from_dict(task["scene"], source=task["label"])
    config = TuningConfig.model_validate(task["config"])
    # The criteria file's path names it in messages and resolves its plugin paths.
    criteria = (criteria_from_text(task["criteria"],
                                   task.get("criteria_source") or "sweep criteria")
                if task.get("criteria") else default_criteria())
    return scene, config, criteria


def _task_budget(task: dict[str, Any], images: Any, config: Any) -> int | None:
    """The budget to search with: the task's, times its ``budget_factor`` (a re-check); a
    budget of None (the strategy's default) is the strategy's planned size times the factor
    (kept None when the strategy does not know its size in advance)."""
    budget, factor = task["budget"], float(task.get("budget_factor", 1.0))
    if factor == 1.0:
        return budget
    if budget is None:
        from ..tune import make_strategy

        budget = make_strategy(task["strategy"], config.space(images.camera), config,
                               task["seed"]).total()
        if budget is None:
            return None
    return max(1, int(round(budget * factor)))


def sensitivity(evaluator: Any, space: Any, best: Any) -> dict[str, Any]:
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
    from ..tune import score_vectors

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
    scores = score_vectors(evaluator, space, xs).score
    s0 = scores[0]
    params: dict[str, Any] = {}
    for name in space.names:
        pts = {f: s for (n, f), s in zip(meta, scores[1:]) if n == name}
        at5 = [pts[f] for f in (-0.05, 0.05) if f in pts]
        drop = (1.0 - float(np.mean(at5)) / s0) if (at5 and s0 > 0) else None
        params[name] = {"scores": [pts.get(f) for f in SENSITIVITY_STEPS], "drop_5pct": drop}
    return {"optimum": s0, "steps": list(SENSITIVITY_STEPS), "params": params}
