"""The sub-solves of many members at once: robust tuning's ``mean`` solve
(:class:`~rvmsim.tune.MembersSolver`) on the nominal image and every variation sample.

Each member's :class:`~rvmsim.tune.EcSolver` would map its outline points and run every
solve, twice, on its own.  :class:`StackedSolves` maps every member's points in one call,
runs each solve once per round for all members (the EC's
:attr:`SubSolve.solve_stack <rvmsim.criteria.SubSolve>`, image for image the EC's own
solve), keeps each member's solved values as it would, and gives their mean.  It applies
when every member's solver follows one plan (the same criteria and space) and every solve
has a stack form; :meth:`MembersSolver <rvmsim.tune.MembersSolver>` solves member by member
otherwise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..criteria import EcDefinition, StackParams, call_ec, checked_solve_value
from ..errors import CriteriaError
from ..isp import IspParams, OutputSpec, input_to_plane
from .solve import SOLVE_ROUNDS, EcSolver

__all__ = ["StackedSolves"]


@dataclass(frozen=True)
class _Step:
    """One solve of the plan on the members that have points for it."""

    ec: EcDefinition
    param: str
    target: float
    low: float
    high: float
    members: np.ndarray  # (K,) member indices
    points: np.ndarray  # (N,) the members' points, member after member: rows of the
    # stacked solves' distinct fisheye points
    lengths: np.ndarray  # (K,) each member's number of points

    def plane_points(self, xy: np.ndarray, ok: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The members that solve for this candidate (>= 3 points in front of the plane),
        their plane points and segment starts, as :meth:`EcSolver.solve_at` selects them
        (``xy``, ``ok``: the distinct points mapped)."""
        front = ok[self.points]
        if front.all():
            return self.members, xy[self.points], np.concatenate([[0], np.cumsum(self.lengths)])
        counts = np.add.reduceat(front.astype(np.intp), np.cumsum(self.lengths) - self.lengths)
        good = counts >= 3
        keep = front & np.repeat(good, self.lengths)
        starts = np.concatenate([[0], np.cumsum(counts[good])])
        return self.members[good], xy[self.points[keep]], starts


class StackedSolves:
    """Every member's sub-solves at once (see the module docstring).

    Parameters
    ----------
    solvers : sequence of EcSolver
        One per member.

    Attributes
    ----------
    applies : bool
        The solvers share one plan and fisheye size, and every solve has a stack form.
    """

    def __init__(self, solvers: Sequence[EcSolver]):
        self.solvers = list(solvers)
        first = self.solvers[0]
        self.applies = all(s.plan == first.plan and s.input_size == first.input_size
                           for s in self.solvers) and all(
            p.ec.sub_solve is not None and p.ec.sub_solve.solve_stack is not None
            for s in self.solvers for p in s.solves)
        self.output: OutputSpec = first.output
        self.input_size = first.input_size
        steps = []
        for ec_id, param, target, low, high in first.plan if self.applies else ():
            found = [(m, p) for m, s in enumerate(self.solvers) for p in s.solves
                     if p.ec.id == ec_id]
            if found:
                steps.append((found[0][1].ec, param, target, low, high,
                              np.array([m for m, _ in found]), [p.points for _, p in found]))
        # the members' outlines overlap (a sample moves an object by a few pixels): each
        # distinct fisheye point is mapped once per candidate
        every = [pts for step in steps for pts in step[6]]
        self._points, inverse = (np.unique(np.concatenate(every), axis=0, return_inverse=True)
                                 if every else (np.zeros((0, 2)), np.zeros(0, np.intp)))
        self._steps: list[_Step] = []
        at = 0
        for ec, param, target, low, high, members, pts in steps:
            size = sum(len(p) for p in pts)
            self._steps.append(_Step(ec, param, target, low, high, members,
                                     inverse.reshape(-1)[at : at + size],
                                     np.array([len(p) for p in pts])))
            at += size
        names = list(dict.fromkeys(n for s in self.solvers for n in s.names))
        #: Per solved parameter, the members whose solver sets it (they make its mean).
        self._setters = {n: [m for m, s in enumerate(self.solvers) if n in s.names]
                         for n in names}

    def __call__(self, params: IspParams) -> IspParams:
        """``params`` with each solved parameter the mean of the members' solved values.
        Without the rotations only (``h_pan``, ``tilt``, ``theta`` 0: then a point's plane
        point is a function of that point alone, :meth:`MembersSolver._each`)."""
        xy, ok = input_to_plane(params, self._points, self.input_size)
        n = len(self.solvers)
        current = {name: np.full(n, float(getattr(params, name))) for name in self._setters}
        steps = [(st, *st.plane_points(xy, ok)) for st in self._steps]
        for _ in range(SOLVE_ROUNDS):
            for st, members, pts, starts in steps:
                if len(members):
                    self._solve(st, params, current, members, pts, starts)
        return params.replace(**{name: float(np.mean([current[name][m] for m in who]))
                                 for name, who in self._setters.items()})

    def _solve(self, st: _Step, params: IspParams, current: dict[str, np.ndarray],
               members: np.ndarray, pts: np.ndarray, starts: np.ndarray) -> None:
        """One solve on ``members``, their values of its parameter set in ``current``."""
        hook = st.ec.sub_solve
        assert hook is not None and hook.solve_stack is not None  # see applies
        seen = StackParams(params, {k: v[members] for k, v in current.items()}, len(members))
        got = call_ec(st.ec, "sub-solve", "a candidate's plane points", hook.solve_stack, pts,
                      starts, seen, self.output, st.target)
        values = np.asarray(got, dtype=np.float64).reshape(-1)
        if len(values) != len(members):
            raise CriteriaError(st.ec.plugin or "<ec>", st.ec.id,
                                f"the sub-solve's solve_stack returned {len(values)} values "
                                f"for {len(members)} images")
        column = current[st.param]
        for m, v in zip(members, values):
            value = checked_solve_value(st.ec, "solve", None if np.isnan(v) else float(v))
            if value is not None:  # an equal value stored again changes nothing
                column[m] = float(min(max(value, st.low), st.high))
