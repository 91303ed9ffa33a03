"""Multi-member evaluation: one candidate judged on several label images at once.

A *member* is one fisheye label image with its camera: for shared tuning one per vehicle
or variant (:func:`rvmsim.tune.tune` with several scenes), for robust tuning one per
variation sample of one scene.  Every member is evaluated with its own
evaluator (:func:`rvmsim.pipeline.make_evaluator`, in the worker processes, as for one scene),
and the members' verdicts are combined into the one trial the run store and the strategy
see:

- **EC score** (the stored ``score``): the :class:`Aggregate` of the members' EC scores,
  by default the minimum (a sign-off must pass on every vehicle, so the worst one is the
  score), or a low quantile (``quantile 0.1``: a setting may lose the worst tenth).
- **passed**: every member passes every enabled EC.
- **ec** (the stored EC column): per EC the member that scores it worst (its value and
  score), passed where it passes on every member, so ``failing()`` lists every EC that
  fails on some member.  Each member's own results are stored too (the ``members`` table
  of :class:`~rvmsim.tune.RunStore`).
- **objective** (what the strategy maximises): for ``min``, the minimum over members of the
  log-score minus ``PASS_WEIGHT`` times the range violations summed over *all* members
  (:data:`OBJECTIVE_COMBINE`; every failing member keeps pulling, not only the worst); for a
  quantile, that quantile of the members' own objectives.
- **sub-solves** (``cmaes-solved``): each member's :class:`~rvmsim.tune.EcSolver` solves
  the candidate and the solved parameters are the mean over members (:class:`MembersSolver`,
  ``mean``): each pinned EC then sits in the middle of the members' spread, which leaves
  the most margin to every member; ``first`` solves on the first (nominal) member only.

With one member none of this runs: :func:`rvmsim.tune.search_scene` is the one-scene path.
"""

from __future__ import annotations

import json
import re
from collections import Counter
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from ..criteria import Criteria
from ..errors import RvmsimError
from ..isp import IspParams, OutputSpec, input_to_plane
from ..pipeline import ImageEvaluator, ImagesEvaluator, make_evaluator
from .objective import (PASS_WEIGHT, ParamsScores, ScoredBatch, check_objective, score_params,
                        score_values)
from ..runs.records import params_json
from .solve import EcSolver
from .stacked_solve import StackedSolves
from ..search.space import SearchSpace

if TYPE_CHECKING:
    from ..camera import FisheyeCamera
    from ..robust import StationReading
    from ..scene import Scene
    from ..runs.store import RunStore
    from .compensated import MembersCompensation

__all__ = ["member_passes", "member_conflicts", "Member", "Aggregate", "parse_aggregate", "MembersSolver", "MembersScorer",
           "check_members", "check_cameras", "worst_ec_json", "member_evaluators", "SOLVE_MODES", "OBJECTIVE_COMBINE", "COMBINES"]

#: How the sub-solves of several members combine (:class:`MembersSolver`).
SOLVE_MODES = ("mean", "first")
#: How the ``min`` aggregate combines the members' pass-first objectives by default:
#: ``sum-violation`` (min log-score − PASS_WEIGHT · Σ over members of their violations; the
#: other choice, ``min``, is the minimum of the members' own objectives).
OBJECTIVE_COMBINE = "sum-violation"
#: The choices of ``combine``.
COMBINES = ("sum-violation", "min")


@dataclass(frozen=True)
class Member:
    """One label image a candidate is judged on: its name (the vehicle, a market, or a
    sample's label), the fisheye label image (H_i, W_i) uint8, the camera that saw it, the
    scene (for ECs that read its geometry; None when unknown), for a sample of a robust run
    with compensation what the end-of-line station has of its car, and the criteria it is
    judged with when they are its own (a market's)."""

    name: str
    labels: np.ndarray
    camera: FisheyeCamera
    scene: Scene | None = None
    station: StationReading | None = None
    #: The member's own criteria (a market's, :mod:`rvmsim.markets`); None: the run's.
    criteria: Criteria | None = None


@dataclass(frozen=True)
class Aggregate:
    """How the members' EC scores make the candidate's: ``min``, or ``quantile`` ``q``
    (0 < q < 1; the members' score at that quantile, taken as the member value just below
    it: ``numpy.quantile(..., method="lower")``)."""

    kind: str = "min"
    q: float = 0.0

    @property
    def text(self) -> str:
        """As ``--aggregate`` takes it and the run settings record it."""
        return "min" if self.kind == "min" else f"quantile {self.q:g}"

    def reduce(self, values: np.ndarray) -> np.ndarray:
        """(M, n) member values → (n,) aggregate."""
        if self.kind == "min":
            return values.min(axis=0)
        return np.quantile(values, self.q, axis=0, method="lower")


def parse_aggregate(text: str | Aggregate) -> Aggregate:
    """``min`` or ``quantile Q`` (also ``quantile=Q``, ``qQ``) as an :class:`Aggregate`.

    Raises
    ------
    RvmsimError
        One line naming ``--aggregate``.
    """
    if isinstance(text, Aggregate):
        return text
    t = str(text).strip().lower()
    if t == "min":
        return Aggregate()
    m = re.fullmatch(r"(?:quantile|q)\s*[= :]?\s*([0-9.eE+-]+)", t)
    q = None
    if m:
        try:
            q = float(m.group(1))
        except ValueError:
            q = None
    if q is None or not 0.0 < q < 1.0:
        raise RvmsimError(f"--aggregate {text!r}: give min, or quantile Q with 0 < Q < 1 "
                          "(e.g. quantile 0.1)")
    return Aggregate("quantile", q)


def check_members(members: Sequence[Member]) -> None:
    """Refuse members that cannot share one search space: none, or cameras of different
    sensor sizes (the space is fitted to the first member's camera; :func:`check_cameras`).

    Raises
    ------
    RvmsimError
        One line naming the member that differs.
    """
    if not members:
        raise RvmsimError("no members to evaluate on")
    check_cameras([(m.name, m.camera) for m in members])


def check_cameras(cameras: Sequence[tuple[str, FisheyeCamera]]) -> None:
    """Refuse named cameras of different sensor sizes: one ISP setting is tuned for one
    camera part, and the search space is fitted to the first camera.

    Raises
    ------
    RvmsimError
        One line naming the first camera that differs from the first one.
    """
    name0, cam0 = cameras[0]
    for name, cam in cameras[1:]:
        if (cam.width, cam.height) != (cam0.width, cam0.height):
            raise RvmsimError(
                f"{name}: camera of {cam.width}x{cam.height} px, but {name0} has "
                f"{cam0.width}x{cam0.height} px: a shared setting needs one sensor size")


class MembersSolver:
    """The sub-solves for several members: each member's :class:`EcSolver` sets its
    parameters, and ``mode`` combines them (``mean``: the mean over the members that solve
    a parameter; ``first``: the first member's).  Picklable."""

    def __init__(self, solvers: Sequence[EcSolver], mode: str = "mean"):
        if mode not in SOLVE_MODES:
            raise ValueError(f"unknown solve mode {mode!r} (known: {', '.join(SOLVE_MODES)})")
        self.solvers = list(solvers) if mode == "mean" else list(solvers[:1])
        self.mode = mode
        names: list[str] = []
        for s in self.solvers:
            names += [n for n in s.names if n not in names]
        self.names = tuple(names)
        sizes = {s.input_size for s in self.solvers}
        self._size = sizes.pop() if len(sizes) == 1 else None
        ends = np.cumsum([0] + [len(s.points) for s in self.solvers])
        self._parts = [slice(int(a), int(b)) for a, b in zip(ends, ends[1:])]
        self._points = (np.concatenate([s.points for s in self.solvers]) if self.solvers
                        else np.zeros((0, 2)))
        stacked = StackedSolves(self.solvers) if len(self.solvers) > 1 else None
        #: Every member's solves at once (None: member by member).
        self._stacked = stacked if stacked is not None and stacked.applies else None

    def _each(self, params: IspParams) -> list[IspParams]:
        """Each solver's solution.  Without the rotations (the paper's setting) the plane
        point of a fisheye point is a function of that point alone
        (:func:`rvmsim.isp.input_to_plane`), so every solver's points are mapped in one call
        and each solver gets its own rows, exactly as it would map them; with rotations each
        maps its own (a matrix product, whose rounding need not be the same per row in a
        larger batch)."""
        if self._size is None or not params.h_pan == params.tilt == params.theta == 0.0:
            return [s(params) for s in self.solvers]
        xy, ok = input_to_plane(params, self._points, self._size)
        return [s.solve_at(params, xy[part], ok[part])
                for s, part in zip(self.solvers, self._parts)]

    def __call__(self, params: IspParams) -> IspParams:
        if len(self.solvers) == 1:
            return self.solvers[0](params)
        if (self._stacked is not None and self._size is not None
                and params.h_pan == params.tilt == params.theta == 0.0):
            return self._stacked(params)
        solved = [(s.names, p) for s, p in zip(self.solvers, self._each(params))]
        values = {}
        for n in self.names:
            got = [getattr(p, n) for names, p in solved if n in names]
            values[n] = float(np.mean(got))
        return params.replace(**values)


def worst_ec_json(member_ecs: Sequence[str]) -> str:
    """The trial's ``ec`` column from its members' (:func:`rvmsim.tune.ec_json` texts): per
    EC the value and score of the member that scores it lowest (the first such), passed
    where every member that judges it passes it; ECs in the order the members first name
    them (members with their own criteria judge different ECs)."""
    docs = [json.loads(e) for e in member_ecs]
    out = {}
    ids = list(dict.fromkeys(ec for d in docs for ec in d))  # members may judge other ECs
    for ec in ids:
        cells = [d[ec] for d in docs if ec in d]
        worst = min(range(len(cells)), key=lambda k: cells[k][1])
        out[ec] = [cells[worst][0], cells[worst][1], all(c[2] for c in cells)]
    return json.dumps(out)


class MembersScorer:
    """``xs → ScoredBatch`` over several members (see the module docstring): what a
    :class:`~rvmsim.tune.BatchEvaluator` runs in its workers for a multi-member search.
    Picklable (each worker holds every member's evaluator)."""

    def __init__(self, evaluators: Sequence[ImageEvaluator] | ImagesEvaluator,
                 space: SearchSpace,
                 solver: Callable[[IspParams], IspParams] | None = None,
                 objective: str = "log-score", aggregate: Aggregate = Aggregate(),
                 combine: str = OBJECTIVE_COMBINE,
                 compensation: MembersCompensation | None = None):
        check_objective(objective)
        if combine not in COMBINES:
            raise ValueError(f"unknown combine {combine!r} (known: {', '.join(COMBINES)})")
        #: Every member's evaluation of a candidate with one map (its batches made on
        #: first use, in the worker).
        self.images = (evaluators if isinstance(evaluators, ImagesEvaluator)
                       else ImagesEvaluator(evaluators))
        self.evaluators = self.images.evaluators
        self.space = space
        self.solver = solver
        self.objective = objective
        self.aggregate = aggregate
        self.combine = combine
        self.compensation = compensation

    def __call__(self, xs: Sequence[np.ndarray]) -> ScoredBatch:
        params = [self.space.params(x) for x in xs]
        if self.solver is not None:
            params = [self.solver(p) for p in params]
        per = self._per_member(params)
        weight = PASS_WEIGHT if self.objective == "pass-first" else 0.0
        member_obj = np.array([m.log_score - weight * m.violation for m in per])
        score = self.aggregate.reduce(np.array([m.score for m in per]))
        if self.aggregate.kind == "min" and self.combine == "sum-violation":
            objective = (np.array([m.log_score for m in per]).min(axis=0)
                         - weight * np.array([m.violation for m in per]).sum(axis=0))
        else:
            objective = self.aggregate.reduce(member_obj)
        passed = np.asarray(np.array([m.passed for m in per]).all(axis=0))
        members = [[(float(m.score[i]), float(member_obj[k, i]), bool(m.passed[i]),
                     m.ec_json[i]) for k, m in enumerate(per)] for i in range(len(params))]
        return ScoredBatch(score.tolist(), objective.tolist(), passed.tolist(),
                           [params_json(p) for p in params],
                           [worst_ec_json([row[3] for row in r]) for r in members], members)


    def _per_member(self, params: list[IspParams]) -> list[ParamsScores]:
        """Each member's scores of the candidates: with compensation, each sample member
        judged with its per-car values, failing where the station rejects the car."""
        if self.compensation is None:  # one map per candidate for every member
            found = [self.images.values(p) for p in params]
            return [score_values(np.array([row[m] for row in found]).reshape(
                len(params), len(ev.criteria.ids)), ev.criteria)
                for m, ev in enumerate(self.evaluators)]
        comp = self.compensation
        nominal = {n: score_params(self.evaluators[n], params) for n in comp.nominal}
        cars = comp.cars(params, np.array([nominal[n].passed for n in comp.nominal]))
        per = []
        for m, (ev, row) in enumerate(zip(self.evaluators, cars)):
            if m in nominal:
                per.append(nominal[m])
                continue
            s = score_params(ev, [p if c is None else c.params for p, c in zip(params, row)])
            rejected = np.array([c is not None and not c.accepted for c in row])
            if rejected.any():
                s = ParamsScores(s.score, s.log_score, s.violation + rejected,
                                 s.passed & ~rejected, s.ec_json)
            per.append(s)
        return per


def member_evaluators(members: Sequence[Member], output: OutputSpec,
                      criteria: Criteria) -> ImagesEvaluator:
    """The members' evaluator (:func:`rvmsim.pipeline.make_evaluator`) on the run's RVM
    ``output``: each member judged by its own criteria or else ``criteria``."""
    return make_evaluator(list(members), output, criteria)


# ---------------------------------------------------------------------------- conflicts
def member_passes(store: RunStore, n: int) -> list[set[int]]:
    """Per member of a search of ``n`` members, the trials it passes (from the store's
    ``members`` table; a run of one member has none: its trials are the member's)."""
    if n == 1:
        return [{int(r[0]) for r in store.rows("SELECT idx FROM trials WHERE passed = 1")}]
    out: list[set[int]] = [set() for _ in range(n)]
    for idx, member in store.rows("SELECT idx, member FROM members WHERE passed = 1"):
        if 0 <= int(member) < n:
            out[int(member)].add(int(idx))
    return out


def _failing_where(store: RunStore, trials: set[int], member: int, name: str,
                   limit: int = 3) -> list[dict[str, Any]]:
    """The ECs of ``member`` (called ``name``) that fail most often in ``trials`` (the
    trials another member passes; from its own results there)."""
    counts: Counter[str] = Counter()
    rows = store.rows("SELECT idx, ec FROM members WHERE member = ?", (member,))
    for idx, ec in rows:
        if int(idx) in trials:
            for k, cell in json.loads(ec).items():
                if not cell[2]:
                    counts[k] += 1
    return [{"member": name, "ec": k, "fails_in": n, "of": len(trials)}
            for k, n in counts.most_common(limit)]


def member_conflicts(store: RunStore, names: Sequence[str],
                     passes: list[set[int]] | None = None) -> list[dict[str, Any]]:
    """Pairs of members (by ``names``, in the search's order) that each pass alone in some
    trial but never together, with the ECs of the other that fail in the trials where one
    passes, most often first: ``{"members": [a, b], "ecs": [{"member", "ec", "fails_in",
    "of"}, …]}`` each.  ``passes``: :func:`member_passes`, when already read."""
    per = passes if passes is not None else member_passes(store, len(names))
    found = []
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            if i < j and per[i] and per[j] and not per[i] & per[j]:
                found.append({"members": [a, b],
                              "ecs": _failing_where(store, per[i], j, b)
                              + _failing_where(store, per[j], i, a)})
    return found
