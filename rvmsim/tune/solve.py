"""Closed-form sub-solves: the parameters that one EC each pins, set per candidate (the
paper's future work 3, dimension reduction).

An EC whose definition has a sub-solve (:attr:`EcDefinition.sub_solve
<rvmsim.criteria.EcDefinition>`, a :class:`~rvmsim.criteria.SubSolve`) depends, for a given
view, on one ISP parameter alone, in closed form: among the paper's ECs, the board aspect,
guideline 2's centre offset and guideline 3's height pin the advanced horizontal scale and
the two advanced shifts (:mod:`rvmsim.criteria.solves`).  :class:`EcSolver` maps the fisheye
outline pixels of each such EC's labels onto the virtual plane once per candidate
(:func:`rvmsim.isp.input_to_plane`: a few hundred points) and sets each parameter so that
its EC lands on its target (from the EC's acceptable range).  The search then has as many
dimensions fewer (:class:`~rvmsim.tune.CmaEsSolved`).

A solve applies only where it is sound: its EC is selected and enabled and its definition
(as its plugin defines it: a replacement without a hook does not solve) has a sub-solve;
its range has a target; the parameter is tuned; and the object is in the fisheye image
(>= 3 outline points, and >= 3 of them in front of the plane for a candidate).  A solved
value is clipped to the parameter's search range.  Two ECs that would solve one parameter
are refused (:class:`~rvmsim.errors.CriteriaError`): which one wins would be arbitrary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..criteria import (Criteria, EcDefinition, SubSolve, call_ec, checked_solve_value,
                        outline_points)
from ..errors import CriteriaError
from ..isp import IspParams, OutputSpec, input_to_plane
from ..search.space import ParamRange, SearchSpace

__all__ = ["EcSolver", "PlannedSolve", "SOLVE_ROUNDS"]

#: Every solve runs this many times per candidate, in order (:attr:`SubSolve.order`): a solve
#: that reads a parameter another one sets after it sees that solved value the second time.
SOLVE_ROUNDS = 2


@dataclass(frozen=True)
class PlannedSolve:
    """One sub-solve of an :class:`EcSolver`: the EC, its target, the fisheye outline
    points it maps and the parameter's search range."""

    ec: EcDefinition  # pickles by reference to its plugin, its hook with it
    target: float
    points: np.ndarray  # fisheye px (N, 2)
    low: float
    high: float

    @property
    def hook(self) -> SubSolve:
        hook = self.ec.sub_solve
        assert hook is not None  # only ECs with a sub-solve are solved
        return hook


class EcSolver:
    """Sets, per candidate, the parameters that the criteria's ECs with a sub-solve pin.

    Parameters
    ----------
    fisheye_labels : (H_i, W_i) uint8
        The scene's fisheye label image.
    output : OutputSpec
        The RVM image the ECs are measured on.
    criteria : Criteria
    space : SearchSpace
        The tuned parameters: a solve sets only a tuned parameter, within its range.

    Attributes
    ----------
    names : tuple of str
        The parameters this solver sets (in the order they are solved).
    targets : dict
        EC id → the value its solve aims at.

    Raises
    ------
    CriteriaError
        Two enabled ECs of ``criteria`` would solve the same tuned parameter.

    Picklable (it goes to tuning's worker processes with the evaluator).
    """

    def __init__(self, fisheye_labels: np.ndarray, output: OutputSpec, criteria: Criteria,
                 space: SearchSpace):
        self.input_size = (fisheye_labels.shape[1], fisheye_labels.shape[0])
        self.output = output
        solves = []
        applicable = _applicable(criteria, space)
        for ec, hook, target, r in applicable:
            pts = outline_points(fisheye_labels, hook.labels)
            if len(pts) >= 3:
                solves.append(PlannedSolve(ec, target, pts, r.low, r.high))
        self._solves = tuple(solves)
        # every solve's points in one array, mapped in one call per candidate
        self._points = (np.concatenate([s.points for s in solves]) if solves
                        else np.zeros((0, 2)))
        ends = np.cumsum([0] + [len(s.points) for s in solves])
        self._slices = tuple(slice(int(a), int(b)) for a, b in zip(ends, ends[1:]))
        self.names = tuple(s.hook.param for s in solves)
        self.targets = {s.ec.id: s.target for s in solves}
        #: The solves the criteria and space call for, before the scene's points are
        #: known (EC id, parameter, target, range): equal for one criteria and space.
        self.plan = tuple((ec.id, hook.param, target, r.low, r.high)
                          for ec, hook, target, r in applicable)

    @property
    def solves(self) -> tuple[PlannedSolve, ...]:
        """The solves this scene has points for, in solve order."""
        return self._solves

    @property
    def points(self) -> np.ndarray:
        """Every solve's fisheye outline points, (N, 2) px: what :meth:`solve_at` takes
        mapped onto the plane."""
        return self._points

    def __call__(self, params: IspParams) -> IspParams:
        """``params`` with the solved parameters set (the others unchanged)."""
        if not self._solves:
            return params
        xy_all, ok_all = input_to_plane(params, self._points, self.input_size)
        return self.solve_at(params, xy_all, ok_all)

    def solve_at(self, params: IspParams, xy_all: np.ndarray, ok_all: np.ndarray
                 ) -> IspParams:
        """:meth:`__call__` with :attr:`points` already mapped onto the plane
        (:func:`rvmsim.isp.input_to_plane` of ``params``: ``xy_all``, ``ok_all``)."""
        if not self._solves:
            return params
        planes: dict[int, np.ndarray] = {}
        for k, part in enumerate(self._slices):
            xy, ok = xy_all[part], ok_all[part]
            if np.count_nonzero(ok) >= 3:
                planes[k] = xy[ok]
        current = params
        for _ in range(SOLVE_ROUNDS):
            for k, s in enumerate(self._solves):
                if k not in planes:
                    continue
                value = checked_solve_value(s.ec, "solve", call_ec(
                    s.ec, "sub-solve", "a candidate's plane points", s.hook.solve, planes[k],
                    current, self.output, s.target))
                if value is None:
                    continue
                value = float(min(max(value, s.low), s.high))
                now = getattr(current, s.hook.param)
                # an equal value (and sign: −0.0 is stored as such) changes nothing
                if value != now or math.copysign(1.0, value) != math.copysign(1.0, now):
                    current = current.replace(**{s.hook.param: value})
        return params.replace(**{n: getattr(current, n) for n in self.names})


def _applicable(criteria: Criteria, space: SearchSpace
                ) -> list[tuple[EcDefinition, SubSolve, float, ParamRange]]:
    """(EC, its sub-solve, target, the parameter's range) of every selected, enabled EC with
    a sub-solve whose range has a target and whose parameter is tuned, in solve order
    (:attr:`SubSolve.order`, then the criteria's order).  Independent of the scene."""
    ranges = {r.name: r for r in space.ranges}
    found: list[tuple[EcDefinition, SubSolve, float, ParamRange]] = []
    setter: dict[str, str] = {}
    for ec, hook, target in criteria.sub_solves(ranges):
        if hook.param in setter:
            raise CriteriaError(criteria.source, f"criteria.{ec.id}",
                                f"ECs {setter[hook.param]} and {ec.id} both solve "
                                f"{hook.param}: disable one of them or leave {hook.param} "
                                "untuned")
        setter[hook.param] = ec.id
        found.append((ec, hook, target, ranges[hook.param]))
    return sorted(found, key=lambda x: x[1].order)
