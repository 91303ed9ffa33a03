"""One design point as a task: render its scene, check what is infeasible without search,
tune the ISP, probe the sensitivity.

:func:`run_point` is a pure function of its task dict (the point's scene document, tuning
config, strategy, budget, seed, criteria text, and for a re-check the parameter sets to
start from and the budget factor; :class:`~rvmsim.batch.payloads.PointTask`), so it runs the
same on a local process or a Dask worker; it writes no files except into the worker's render
cache.  :func:`run_yield` measures only the yield of a given setting at a point.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..criteria import criteria_from_text, default_criteria, record_size
from ..errors import RvmsimError
from ..isp import IspParams
from ..markets import market_members, parse_markets
from ..render import cached_render
from ..runs import RunStore
from ..scene import scene_from_dict
from ..tune import SearchSettings, candidate_evaluator, search_scene
from ..search import TuningConfig
from .executors import task_malloc
from .feasibility import infeasible_ecs
from .markets import markets_yield, run_markets_point
from .payloads import (EcOutcomeDoc, PointError, PointResult, PointRun, PointTask, YieldOnly,
                       YieldTask)
from .probes import RENDER_LOCK, sensitivity, task_budget
from .yields import point_yield

if TYPE_CHECKING:
    from ..criteria import Criteria
    from ..runs import TrialRecord
    from ..scene import Scene
    from ..search import SearchSpace
    from .feasibility import Infeasibility

__all__ = ["run_point", "run_yield"]


def run_point(task: PointTask) -> PointResult:
    """Render, tune and probe one design point (runs in a worker; no files but the render
    cache).

    ``task`` (:class:`~rvmsim.batch.payloads.PointTask`) holds ``scene`` (document),
    ``config`` (tuning config document), ``label``, ``strategy``, ``budget``, ``seed``,
    ``criteria`` (text or None), ``criteria_source``, ``sensitivity``, ``robustness``
    (``{"samples", "seed"}`` of the yield, or None: no yield); a re-check adds ``starts``
    (parameter dicts, name → value, evaluated first), ``budget_factor`` (the budget, or the
    strategy's default size when the budget is None, times this), ``beat`` (``(passed,
    score)`` of the point's best so far: the yield is measured only when this run's best
    ranks above it, as only then can it be the point's final best).

    Returns a JSON-ready dict (:class:`~rvmsim.batch.payloads.PointRun`): ``score``,
    ``passed``, ``ecs`` (id → value, score, passed), ``params``, ``tuned``,
    ``evaluations``, ``budget`` (the budget searched with, None for the strategy's
    default), ``stopped``, ``limiting_ec`` (the failing enabled EC with the lowest score,
    or None), ``infeasible`` (the enabled ECs no ISP setting can pass here, as
    ``{"ec", "reason", "short"}``: :func:`~rvmsim.batch.feasibility.infeasible_ecs`),
    ``sensitivity`` (see :func:`sensitivity`), ``robustness`` (the best setting's yield,
    :func:`~rvmsim.batch.yields.point_yield`; only when the task asks for one, the scene
    has a ``variation`` section and the run beats ``beat``) and ``seconds``; a problem
    with the point is returned as ``{"error": message, "seconds"}``.

    A markets sweep's task (``markets``) is tuned for every market at once
    (:func:`~rvmsim.batch.markets.run_markets_point`).
    """
    with task_malloc():
        if task.get("markets"):
            return run_markets_point(task)
        return _run_point(task)


def run_yield(task: YieldTask) -> YieldOnly | PointError:
    """Measure the yield of the task's ``yield_of`` setting at its design point (a result
    stored before yields existed): ``{"robustness", "seconds"}``, or ``{"error", "seconds"}``
    when the point's scene cannot be built (runs in a worker)."""
    with task_malloc():
        return _run_yield(task)


def _run_yield(task: YieldTask) -> YieldOnly | PointError:
    t0 = time.perf_counter()
    if task.get("markets"):
        return _run_markets_yield(task)
    try:
        scene, config, criteria = _task_inputs(task)
        rob = task["robustness"]
        if rob is None:
            raise RvmsimError(f"{task['label']}: a yield task without robustness settings")
        with RENDER_LOCK:
            y = point_yield(scene, IspParams(**task["yield_of"]), config.output_spec(),
                            criteria, rob["samples"], rob["seed"])
        return {"robustness": y, "seconds": time.perf_counter() - t0}
    except RvmsimError as err:
        return {"error": str(err), "seconds": time.perf_counter() - t0}


def _run_markets_yield(task: YieldTask) -> YieldOnly | PointError:
    """:func:`run_yield` for a markets sweep's point: the yield over every market."""

    t0 = time.perf_counter()
    try:
        scene = scene_from_dict(task["scene"], source=task["label"])
        pairs = market_members([scene], parse_markets(task.get("markets", [])))
        config = TuningConfig.model_validate(task["config"]).at_record(
            record_size(pairs[0].criteria, pairs[0].scene))
        rob = task["robustness"]
        if rob is None:
            raise RvmsimError(f"{task['label']}: a yield task without robustness settings")
        y = markets_yield(pairs, IspParams(**task["yield_of"]), config.output_spec(),
                          rob["samples"], rob["seed"])
        return {"robustness": y, "seconds": time.perf_counter() - t0}
    except RvmsimError as err:
        return {"error": str(err), "seconds": time.perf_counter() - t0}


def _run_point(task: PointTask) -> PointResult:
    t0 = time.perf_counter()
    try:
        scene, config, criteria = _task_inputs(task)
        # One render at a time per process: a Dask worker with several threads would
        # otherwise open several OpenGL contexts at once.
        with RENDER_LOCK:
            images, _ = cached_render(scene)
        phases = {"render": time.perf_counter() - t0}
        t = time.perf_counter()
        infeasible = infeasible_ecs(scene, images.camera, images.labels, criteria)
        evaluator = candidate_evaluator(images, config, criteria)
        budget = task_budget(task, images, config)
        starts = [IspParams(**p) for p in task.get("starts", ())]
        # an infeasible point's verdict is proven before any search: one candidate fills
        # its EC columns (it fails the infeasible ECs, as every setting does)
        how = (SearchSettings(config, criteria, "random", task["seed"], 1) if infeasible else
               SearchSettings(config, criteria, task["strategy"], task["seed"], budget,
                              tuple(starts)))
        store = RunStore(":memory:")
        try:
            outcome = search_scene(images, how, store, evaluator=evaluator)
            n_eval = store.count()
        finally:
            store.close()
        best, space = outcome.best, outcome.space
        if best is None:
            raise RvmsimError(f"{task['label']}: the search evaluated no candidate")
        result = _run_doc(best, space, criteria, n_eval, budget,
                          "infeasible" if infeasible else outcome.stopped, infeasible)
        if task.get("sensitivity", True) and not infeasible:
            result["sensitivity"] = sensitivity(evaluator, space, best.params)
        phases["tune"] = time.perf_counter() - t
        t = time.perf_counter()
        rob = task.get("robustness")
        beat = task.get("beat")
        if rob and rob["samples"] > 0 and scene.variation is not None and infeasible:
            result["robustness"] = {"error": "not measured: the point is infeasible ("
                                    + "; ".join(x.reason for x in infeasible) + ")",
                                    "seconds": 0.0}
        elif (rob and rob["samples"] > 0 and scene.variation is not None
                and (beat is None or (result["passed"], result["score"]) > tuple(beat))):
            with RENDER_LOCK:  # renders the variation's viewpoints
                result["robustness"] = point_yield(scene, best.params, config.output_spec(),
                                                   criteria, rob["samples"], rob["seed"])
        phases["yield"] = time.perf_counter() - t
        result["phases"] = phases
        result["seconds"] = time.perf_counter() - t0
        return result
    except RvmsimError as err:
        return {"error": str(err), "seconds": time.perf_counter() - t0}


def _run_doc(best: TrialRecord, space: SearchSpace, criteria: Criteria, n_eval: int,
             budget: int | None, stopped: str, infeasible: Sequence[Infeasibility]
             ) -> PointRun:
    """A run's result from its best trial (see :func:`run_point`)."""
    ecs: dict[str, EcOutcomeDoc] = {  # as EcOutcome.as_dict gives them, typed
        ec: {"value": o.value, "score": o.score, "passed": o.passed}
        for ec, o in best.ecs.items()}
    failing = [(v["score"], ec) for ec, v in ecs.items()
               if not v["passed"] and criteria.items[ec].enabled]
    return {
        "score": best.score,
        "passed": bool(best.passed),
        "ecs": ecs,
        "params": {n: getattr(best.params, n) for n in best.params.names()},
        "tuned": list(space.names),
        "evaluations": n_eval,
        "budget": budget,
        "stopped": stopped,
        "infeasible": [x.as_dict() for x in infeasible],
        "limiting_ec": min(failing)[1] if failing else None,
    }


def _task_inputs(task: PointTask) -> tuple[Scene, TuningConfig, Criteria]:
    """(scene, tuning config, criteria) of a point's task."""

    scene = scene_from_dict(task["scene"], source=task["label"])
    config = TuningConfig.model_validate(task["config"])
    # The criteria file's path names it in messages and resolves its plugin paths.
    text = task.get("criteria")
    criteria = (criteria_from_text(text, task.get("criteria_source") or "sweep criteria")
                if text else default_criteria())
    return scene, config.at_record(record_size(criteria, scene)), criteria
