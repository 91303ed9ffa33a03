"""The two optional hooks of an EC definition: a closed-form sub-solve and a feasibility
reason (:class:`~rvmsim.criteria.EcDefinition`'s ``sub_solve`` and ``infeasibility``).

- A **sub-solve** (:class:`SubSolve`) says that, for a given view, the EC depends on one ISP
  parameter alone in a way that has a closed form: tuning's ``cmaes-solved`` strategy
  (:class:`rvmsim.tune.EcSolver`) then sets that parameter per candidate so that the EC
  lands on a target taken from its acceptable range, and searches one dimension fewer.
- A **feasibility reason** (:data:`InfeasibilityFn`) says, from the fisheye labels and the
  scene alone, why no ISP setting can pass the EC (the ISP only resamples the fisheye image:
  what is not in it, or hidden or cut off in it, stays so whatever the parameters); a design
  sweep (:func:`rvmsim.batch.infeasible_ecs`) then gives the point the verdict
  ``infeasible`` without trusting the search.

Both are plain functions of a plugin, like ``measure``; docs/criteria.md has an example.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..isp import IspParams, OutputSpec
from .sigmoid import Criterion

if TYPE_CHECKING:
    from .context import SceneContext
    from .measure import MeasureOptions

__all__ = ["SubSolve", "SolveFn", "SolveStackFn", "StackParams", "TargetFn", "InfeasibilityFn",
           "range_middle", "range_zero", "ISP_PARAM_NAMES"]

#: The names of the ISP parameters (:class:`rvmsim.isp.IspParams` fields) a sub-solve may set.
ISP_PARAM_NAMES: tuple[str, ...] = tuple(f.name for f in dataclasses.fields(IspParams))

#: ``solve(plane_xy, params, output, target)`` → the parameter's value (None: no solution).
SolveFn = Callable[[np.ndarray, IspParams, OutputSpec, float], "float | None"]
#: ``solve_stack(plane_xy, starts, params, output, target)`` → (K,) values, NaN for none:
#: the solve of K images at once (:class:`SubSolve`).
SolveStackFn = Callable[[np.ndarray, np.ndarray, "StackParams", OutputSpec, float],
                        np.ndarray]
#: ``target(criterion)`` → the value the EC is solved to (None: the range has none).
TargetFn = Callable[[Criterion], "float | None"]
#: ``reason(context, criterion, options)`` → None, or (reason, short) of why no ISP setting
#: can pass the EC: ``reason`` one line, ``short`` a few words for a map cell, both without
#: the EC id (the caller prefixes it).
InfeasibilityFn = Callable[["SceneContext", Criterion, "MeasureOptions"],
                           "tuple[str, str] | None"]


def range_middle(criterion: Criterion) -> float | None:
    """The middle of the acceptable range ``[low, high]``; None when a side is open."""
    if criterion.low is None or criterion.high is None:
        return None
    return (criterion.low + criterion.high) / 2.0


def range_zero(criterion: Criterion) -> float | None:
    """0, for an EC that is best at 0 (an offset, a difference): None when the range has no
    upper bound or its lower bound is above 0."""
    if criterion.high is None or (criterion.low is not None and criterion.low > 0):
        return None
    return 0.0


@dataclass(frozen=True)
class StackParams:
    """A candidate's parameters as the solves of K images see them: ``base``, with the
    values solved so far on each image (``values``: parameter name → (K,) float64)."""

    base: IspParams
    values: dict[str, np.ndarray]
    n: int

    def get(self, name: str) -> np.ndarray:
        """Parameter ``name`` on each image: (K,) float64."""
        got = self.values.get(name)
        return got if got is not None else np.full(self.n, float(getattr(self.base, name)))


@dataclass(frozen=True)
class SubSolve:
    """A closed-form sub-solve: the ISP parameter an EC pins, and how.

    Per candidate, the outline of the fisheye pixels of ``labels`` is mapped onto the ISP's
    virtual image plane (:func:`rvmsim.isp.input_to_plane`, with the candidate's
    parameters), and ``solve`` computes from those plane points the value of ``param`` that
    puts the EC on ``target(criterion)``.

    Parameters
    ----------
    param : str
        The :class:`~rvmsim.isp.IspParams` field the solve sets (e.g. ``"adv_v_shift"``).
    labels : tuple of int
        The fisheye labels whose pixels' outline is mapped (every region of any of them).
    solve : callable
        ``solve(plane_xy, params, output, target) -> float | None``: ``plane_xy`` the mapped
        outline points in front of the plane, (N, 2) float64, N >= 3; ``params`` the
        candidate with the values solved so far (the current values of this and every other
        parameter); ``output`` the RVM image (:class:`~rvmsim.isp.OutputSpec`); ``target``
        the EC value aimed at.  Returns the parameter's value (clipped afterwards to its
        search range), or None when there is no solution (the parameter is left as it is).
    target : callable
        ``target(criterion) -> float | None``: the EC value aimed at, from the criteria's
        acceptable range (default :func:`range_middle`; :func:`range_zero` for an EC best
        at 0); None: no solve with this range.
    order : int
        Solves run in increasing ``order`` (ties: the criteria's EC order), and the whole
        sequence runs twice, so that a solve reading another's parameter sees its solved
        value (e.g. the guidelines' visible parts depend on each other's shift).
    solve_stack : callable, optional
        ``solve_stack(plane_xy, starts, params, output, target) -> (K,) float64``: the solve
        of K images at once (robust tuning solves every variation sample), image k's points
        ``plane_xy[starts[k]:starts[k + 1]]`` (at least 3 each), its parameters
        ``params.get(name)[k]`` (:class:`StackParams`); NaN where there is no solution.
        Image for image exactly what ``solve`` gives.

    Convention
    ----------
    Plane coordinates as :func:`rvmsim.isp.input_to_plane` returns them: output
    half-widths, not mirrored, before the advanced shifts and scales.  An output pixel
    centre (column u, row v; integers) of a W × H image shows the plane point
    ``x = (u − (W − 1)/2) / (s_h · W/2) + adv_h_shift``,
    ``y = (v − (H − 1)/2) / (s_v · W/2) + adv_v_shift`` (s_h, s_v the advanced scales), so
    a box spanning Δx on the plane is ``Δx · s_h · W/2 + 1`` px wide, and an EC given as a
    percentage of the height at row v is ``100 · (v + 0.5) / H``.
    """

    param: str
    labels: tuple[int, ...]
    solve: SolveFn
    target: TargetFn = range_middle
    order: int = 0
    solve_stack: SolveStackFn | None = None

    def __post_init__(self) -> None:
        if self.param not in ISP_PARAM_NAMES:
            raise ValueError(f"sub-solve: param must be an ISP parameter "
                             f"({', '.join(ISP_PARAM_NAMES)}), got {self.param!r}")
        labels = tuple(self.labels) if isinstance(self.labels, (list, tuple)) else None
        if not labels or not all(isinstance(x, (int, np.integer)) and not isinstance(x, bool)
                                 and 0 <= x <= 255 for x in labels):
            raise TypeError(f"sub-solve of {self.param}: labels must be a non-empty tuple of "
                            "label ids 0..255")
        object.__setattr__(self, "labels", tuple(int(x) for x in labels))
        if self.solve_stack is not None and not callable(self.solve_stack):
            raise TypeError(f"sub-solve of {self.param}: solve_stack must be a function")
        for key in ("solve", "target"):
            if not callable(getattr(self, key)):
                raise TypeError(f"sub-solve of {self.param}: {key} must be a function")
        if not isinstance(self.order, int) or isinstance(self.order, bool):
            raise TypeError(f"sub-solve of {self.param}: order must be an integer")
