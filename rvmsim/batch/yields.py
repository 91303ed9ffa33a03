"""A design point's yield: the share of production variation samples on which its tuned
setting passes every enabled EC (:func:`rvmsim.robust.robustness`), as the sweep stores and
tabulates it.

Sweep file (top level)::
    robustness: {samples: 64, seed: 0}    # the defaults; samples: 0 turns the yield off

A point gets a yield when its scene has a ``variation`` section (the base scene's, or one
a sweep axis sets).  It is measured inside the point's task, on the final best setting of
the run that found it (:func:`rvmsim.batch.point.run_point`; a re-check measures it only when
its best beats the point's best so far, so the final best always carries its yield), and is
stored with the run's result in ``sweep.sqlite``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pydantic import BaseModel, ConfigDict, Field

from ..errors import RvmsimError
from .payloads import MergedPoint, PointRun, YieldDoc, YieldError
from ..robust import RobustnessSettings, robustness

if TYPE_CHECKING:
    from ..criteria import Criteria
    from ..isp import IspParams, OutputSpec
    from ..robust import RobustnessResult
    from ..scene import Scene

__all__ = ["YieldSettings", "YieldModel", "MAX_YIELD_SAMPLES", "YIELD_COLUMNS", "point_yield",
           "yield_summary", "yield_cells", "yield_problem"]

#: Most variation samples of a design point's yield (``robustness.samples``).
MAX_YIELD_SAMPLES = 4096

#: The yield columns of sweep.csv (and keys of each point in sweep.json), in order.
YIELD_COLUMNS = ("yield", "yield_ci_low", "yield_ci_high", "yield_limiting_ec",
                 "yield_limiting_fail_rate", "yield_limiting_axis")


class YieldModel(BaseModel):
    """The sweep file's ``robustness`` section (validated at load)."""

    model_config = ConfigDict(extra="forbid", strict=True)
    samples: int = Field(default=64, ge=0, le=MAX_YIELD_SAMPLES)
    seed: int = Field(default=0, ge=0, le=2**32 - 1)


@dataclass(frozen=True)
class YieldSettings:
    """How a sweep measures each design point's yield (``robustness``): ``samples``
    variation samples at tolerance scale 1 (0: no yield), Sobol seed ``seed``.  Only points
    whose scene has a ``variation`` section get one."""

    samples: int = 64
    seed: int = 0


def point_yield(scene: Scene, params: IspParams, output: OutputSpec, criteria: Criteria,
                samples: int, seed: int, render_scale: float = 1.0) -> YieldDoc | YieldError:
    """The yield of ``params`` at one design point, JSON-ready (:func:`yield_summary`), or
    ``{"error": message}`` when it cannot be measured (the tuning result is kept).

    Parameters
    ----------
    scene : Scene
        The point's scene (its ``variation`` section gives the samples).
    params : IspParams
        The point's best setting, for the full sensor.
    output : OutputSpec
        The RVM image the ECs are measured on (the sweep's tuning config).
    criteria : Criteria
    samples, seed : int
        Variation samples at tolerance scale 1 and their Sobol seed.
    render_scale : float
        Fraction of the sensor rendered: 1, as the point's tuning renders it.
    """

    t0 = time.perf_counter()
    settings = RobustnessSettings(output, criteria, samples=samples, seed=seed, scales=(1.0,),
                                  render_scale=render_scale)
    try:
        res = robustness(scene, params, settings, frames=False)
    except RvmsimError as err:
        return {"error": f"yield: {err}", "seconds": time.perf_counter() - t0}
    return {**yield_summary(res), "seconds": time.perf_counter() - t0}


def yield_summary(res: RobustnessResult) -> YieldDoc:
    """What a sweep keeps of a :class:`~rvmsim.robust.RobustnessResult`: ``yield``,
    ``ci95`` (Wilson, [low, high]), ``n_pass``, ``n``, ``seed``; ``limiting_ec`` (the enabled
    EC failing on most samples, the first in the criteria's order among equals; None when
    none fails), its ``limiting_fail_rate``, ``limiting_axis`` and ``limiting_driver`` (the
    axis driving its failures, :attr:`~rvmsim.robust.EcStats.driver`, and its description;
    None when no axis does), and ``failure_rates`` (enabled EC id → share of samples
    failing)."""
    enabled = [e for e in res.ecs if e.enabled]
    failing = [e for e in enabled if e.n_fail]
    top = max(failing, key=lambda e: e.failure_rate) if failing else None
    driver = top.driver if top is not None else None
    est = res.estimate
    return {"yield": est.yield_, "ci95": [est.ci[0], est.ci[1]], "n_pass": est.n_pass,
            "n": est.n, "seed": res.seed,
            "limiting_ec": None if top is None else top.id,
            "limiting_fail_rate": None if top is None else top.failure_rate,
            "limiting_axis": None if driver is None else driver.axis,
            "limiting_driver": None if driver is None else driver.describe(),
            "failure_rates": {e.id: e.failure_rate for e in enabled}}


def yield_cells(result: PointRun | MergedPoint) -> list[float | str | None]:
    """A point result's :data:`YIELD_COLUMNS` values (all None without a measured yield)."""
    y = result.get("robustness")
    if not isinstance(y, Mapping) or "error" in y:
        return [None] * len(YIELD_COLUMNS)
    return [y["yield"], y["ci95"][0], y["ci95"][1], y.get("limiting_ec"),
            y.get("limiting_fail_rate"), y.get("limiting_axis")]


def _num(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def yield_problem(y: object) -> str | None:
    """What is wrong with a stored point's ``robustness`` entry (None: it is one
    :func:`point_yield` returns, as far as the outputs read it)."""
    if not isinstance(y, dict):
        return "not a JSON object"
    if "error" in y:
        return None if isinstance(y["error"], str) else "error: not a text"
    ci = y.get("ci95")
    if not (_num(y.get("yield")) and isinstance(ci, list) and len(ci) == 2
            and all(_num(c) for c in ci)):
        return "yield, ci95: not numbers"
    if not (y.get("limiting_ec") is None or isinstance(y["limiting_ec"], str)):
        return "limiting_ec: not a text"
    if not (y.get("limiting_fail_rate") is None or _num(y["limiting_fail_rate"])):
        return "limiting_fail_rate: not a number"
    if not (y.get("limiting_axis") is None or isinstance(y["limiting_axis"], str)):
        return "limiting_axis: not a text"
    return None
