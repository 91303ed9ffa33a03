"""The per-car laws: from a car's station reading and picture to the values the end-of-line
step writes, and the station's verdict on them.

``law: ec-solve`` (:class:`EcSolveLaw`, the default) judges each car by what its picture is
judged by, the ECs themselves:

1. **Start.** The reference-point law's values (:class:`rvmsim.compensation.
   CompensationLaw`: ground points held where the nominal car shows them), and the platform
   values themselves (a car that passes as it is must not be made worse): the better of
   the two by the least margin.
2. **Search.** Nelder–Mead (``scipy.optimize.minimize``) over the written values' offsets
   (the pans' turn as a 2-vector, the tilt, shifts where the model names them), within the
   allowed ranges, maximising the least normalised EC margin (:mod:`.margins`) on the car's
   picture (:mod:`.picture`), for at most the model's ``budget`` EC evaluations.  A written
   parameter that an enabled EC pins in closed form (its sub-solve,
   :class:`rvmsim.criteria.SubSolve`) is set by that solve for every candidate instead of
   searched.
3. **Feasibility.** A car that still fails is checked on a grid of the allowed ranges
   (:mod:`.conflicts`): a grid point that passes restarts the search there; none passing
   makes the car *infeasible*, with the ECs that conflict named.
4. **Verdict.** ``pass``, ``marginal`` (every EC passes, one by less than the station's
   uncertainty of that EC: :mod:`.uncertainty`) or ``infeasible``.

``law: reference-points`` (:class:`ReferencePointsLaw`) writes the reference-point law's
values as they are (clipped to the ranges; a car that needs more fails, "EOL range
exceeded"), and judges them on the same picture.

Both return a :class:`CarSolution`; one call serves ``rvmsim robustness --compensation``,
``tune --robust --compensation`` and ``rvmsim eol`` (each hands it the car's picture), so the
three write the same values for the same car and picture.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..compensation import CompensationLaw, Correction, Deviation
from ..criteria import (Criteria, EcDefinition, SubSolve, call_ec, checked_solve_value,
                        outline_points, score_batch)
from ..isp import IspParams, OutputSpec, input_to_plane
from .conflicts import GRID_LEVELS, conflicts_on_grid, grid_of
from .margins import MarginScale
from .picture import CarPicture

__all__ = ["CarSolution", "EcSolveLaw", "ReferencePointsLaw", "PerCarLaw", "STATUSES",
           "INITIAL_STEP", "STOP_TOLERANCE", "STOP_SIGMAS"]

#: What the station says of a car: every EC passes (``pass``), passes but one inside its
#: uncertainty (``marginal``), fails (``fail``: a reference-point law's values), or no
#: setting within the allowed ranges passes (``infeasible``).
STATUSES = ("pass", "marginal", "fail", "infeasible")
#: How far below the nominal car's least normalised margin a car may stay and the search
#: stop (``stop: nominal``): half the unit of :mod:`.margins` (for EC 2-3, 0.43 px).
STOP_TOLERANCE = 0.5
#: The margin, in the station's σ of each EC, every EC needs before the search stops early.
STOP_SIGMAS = 3.0
#: The search's first step along each variable, in the variable's typical size
#: (:attr:`rvmsim.compensation.CompensationLaw.scales`: 0.25° for the pans and tilt).
INITIAL_STEP = 0.25


@dataclass(frozen=True)
class CarSolution:
    """One car's per-car values and the station's verdict on them.

    Attributes
    ----------
    correction : Correction
        The written values (``correction.params``: the car's whole setting) and, for the
        reference-point start, its residuals.
    values : (k,) float64
        The EC values on the car's picture with those values (criteria's ids order).
    margins : (k,) float64
        Each EC's signed margin, its own unit (NaN: binary, or not measured).
    uncertainty : (k,) float64
        The station's 1 σ of each EC's value (0 where not known).
    status : str
        One of :data:`STATUSES`.
    reasons : tuple of str
        Why a car is not ``pass`` (failing ECs, range exceeded, marginal ECs, conflicts).
    evaluations : int
        EC evaluations the law spent on the car.
    start : Correction
        The reference-point law's values (the search's start).
    law : str
    """

    correction: Correction
    values: np.ndarray
    margins: np.ndarray
    uncertainty: np.ndarray
    status: str
    reasons: tuple[str, ...] = ()
    evaluations: int = 0
    start: Correction | None = None
    law: str = "ec-solve"
    ids: tuple[str, ...] = field(default=())

    @property
    def params(self) -> IspParams:
        """The car's full ISP setting (full sensor)."""
        return self.correction.params

    def as_dict(self) -> dict[str, object]:
        """JSON-ready (robustness.json's and eol.json's per-car rows)."""
        def num(x: float) -> float | None:
            return None if not math.isfinite(x) else round(float(x), 4)

        return {"law": self.law, "status": self.status, "reasons": list(self.reasons),
                "evaluations": self.evaluations, **self.correction.as_dict(),
                "station_ecs": {ec: {"value": num(v), "margin": num(m), "sigma": num(s)}
                                for ec, v, m, s in zip(self.ids, self.values, self.margins,
                                                       self.uncertainty)},
                "start": None if self.start is None else self.start.as_dict()}


class _Budget(Exception):
    """The law's evaluations are spent, or the margin is enough (stops the search)."""


class PerCarLaw:
    """What both laws share: the reference-point law, the criteria and their margins, the
    station's EC uncertainty and its policy for marginal cars.

    Parameters
    ----------
    reference : CompensationLaw
        The reference-point law of the platform setting (its model: ranges, budget, policy).
    criteria : Criteria
    output : OutputSpec
        The RVM image of record (the sub-solves' plane scale).
    uncertainty : (k,) float, optional
        The station's 1 σ per EC (:func:`rvmsim.percar.ec_uncertainty`); default none.
    """

    name = "reference-points"

    def __init__(self, reference: CompensationLaw, criteria: Criteria, output: OutputSpec,
                 uncertainty: np.ndarray | None = None):
        self.reference = reference
        self.model = reference.model
        self.criteria = criteria
        self.output = output
        self.scale = MarginScale.of(criteria)
        k = len(criteria.ids)
        self.uncertainty = (np.zeros(k) if uncertainty is None
                            else np.asarray(uncertainty, dtype=np.float64).reshape(k))
        #: The nominal car's least normalised margin with the platform setting (None:
        #: unknown; :func:`rvmsim.percar.make_law` reads it on the nominal picture).
        self.target: float | None = None

    def settled(self, values: np.ndarray) -> bool:
        """Whether ``values`` ((k,)) are good enough for the search to stop (model
        ``stop: nominal``): every EC passes by :data:`STOP_SIGMAS` of the station's
        uncertainty of it, and the least normalised margin is at least :attr:`target` (the
        nominal car's) less :data:`STOP_TOLERANCE`."""
        if self.model.stop != "nominal" or self.target is None:
            return False
        if not self.scale.passed(values)[0] or float(
                self.scale.least(values, self.uncertainty)[0]) < self.target - STOP_TOLERANCE:
            return False
        m = self.scale.margins(values)[0]
        with np.errstate(invalid="ignore"):
            close = self.scale.enabled & (m < STOP_SIGMAS * self.uncertainty)
        return not bool(close.any())

    def accepts(self, solution: CarSolution) -> bool:
        """Whether the station lets the car go (``marginal``: by the model's policy)."""
        return solution.status == "pass" or (solution.status == "marginal"
                                             and self.model.marginal == "accept")

    def solve(self, measured: Deviation, picture: CarPicture) -> CarSolution:
        """The values for a car the station reads as ``measured``, judged on ``picture``."""
        correction = self.reference.correct(measured)
        values = picture.values([correction.params])[0]
        return self._solution(correction, values, 1, correction, list(correction.exceeded))

    def _solution(self, correction: Correction, values: np.ndarray, evaluations: int,
                  start: Correction | None, reasons: list[str], infeasible: bool = False
                  ) -> CarSolution:
        """The verdict on ``values``: failing ECs, then marginal ones."""
        ids = self.criteria.ids
        margins = self.scale.margins(values)[0]
        passed = self.scale.passed(values)[0] and correction.within_range
        failing = [ec for ec, ok, on in zip(ids, score_rows(self.criteria, values),
                                            self.scale.enabled) if on and not ok]
        if failing:
            reasons.append(f"EC {', '.join(failing)} fail{'s' if len(failing) == 1 else ''}")
        status = "infeasible" if infeasible else "pass" if passed else "fail"
        if status == "pass":
            close = [ec for ec, m, s, on in zip(ids, margins, self.uncertainty,
                                                self.scale.enabled)
                     if on and s > 0 and math.isfinite(m) and m < s]
            if close:
                status = "marginal"
                reasons.append("marginal: " + ", ".join(
                    f"EC {ec} margin {m:.3g} < σ {s:.3g}" for ec, m, s in
                    zip(ids, margins, self.uncertainty) if ec in close))
        return CarSolution(correction, np.asarray(values, np.float64), margins,
                           self.uncertainty, status, tuple(reasons), evaluations, start,
                           self.name, ids)


def score_rows(criteria: Criteria, values: np.ndarray) -> np.ndarray:
    """(k,) bool: which ECs pass, for one row of values."""
    return score_batch(np.atleast_2d(values), criteria).passed[0]


class ReferencePointsLaw(PerCarLaw):
    """``law: reference-points``: the reference-point law's values, judged on the picture
    (the module docstring)."""

    name = "reference-points"


class EcSolveLaw(PerCarLaw):
    """``law: ec-solve``: the values that pass every EC with the largest least margin (the
    module docstring)."""

    name = "ec-solve"

    def __init__(self, reference: CompensationLaw, criteria: Criteria, output: OutputSpec,
                 uncertainty: np.ndarray | None = None):
        super().__init__(reference, criteria, output, uncertainty)
        self._solves = _written_solves(criteria, reference)
        solved = {hook.param for _, hook, _ in self._solves}
        names = reference.variables
        self._free = np.array([n not in solved for n in names], bool)
        self._names = tuple(n for n, f in zip(names, self._free) if f)
        low, high = reference.bounds
        self._low, self._high = low[self._free], high[self._free]
        self._typical = reference.scales[self._free]

    @property
    def variables(self) -> tuple[str, ...]:
        """The searched variables (the reference law's, less those a sub-solve sets)."""
        return self._names

    def solve(self, measured: Deviation, picture: CarPicture) -> CarSolution:
        """The values for a car the station reads as ``measured``, judged on ``picture``."""

        x_ref, rms, worst = self.reference.fit(measured)
        start = self.reference.correction_at(x_ref, rms, worst)
        run = _Run(self, picture)
        zero = np.zeros(len(self._names))
        first = self.reference.clip(x_ref)[self._free]
        try:
            run.value(first)
            if np.max(np.abs(first)) > 1e-9:
                run.value(zero)
            x0 = run.best_x
            if len(x0):
                simplex = [x0] + [x0 + INITIAL_STEP * self._typical[i] * np.eye(len(x0))[i]
                                  for i in range(len(x0))]
                minimize(run.scaled, x0 / self._typical, method="Nelder-Mead",
                         bounds=list(zip(self._low / self._typical,
                                         self._high / self._typical)),
                         options={"initial_simplex": np.array(simplex) / self._typical,
                                  "maxfev": 10 ** 6, "xatol": 0.02, "fatol": 1e-3})
        except _Budget:
            pass  # the budget is spent: the best values so far stand
        infeasible = False
        reasons: list[str] = []
        if run.best_least <= 0 and not run.best_passed:
            infeasible, reasons = self._grid(run, picture)
            if infeasible and start.exceeded:  # what holding the site in place would need
                reasons += [f"the reference points need more: {e}" for e in start.exceeded]
        x = self._full(run.best_x, picture, run.outlines)
        correction = self.reference.correction_at(x, rms, worst)
        return self._solution(correction, run.best_values, run.count, start, reasons,
                              infeasible)

    def _grid(self, run: _Run, picture: CarPicture) -> tuple[bool, list[str]]:
        """A failing car's grid check: a passing grid point restarts the search from it
        (with a fresh budget); none passing: infeasible, with the conflicting ECs."""

        pts = grid_of(self.reference, self._free, GRID_LEVELS)
        values = picture.values([self.params_at(x, picture, run.outlines) for x in pts])
        run.count += len(pts)
        least = self.scale.least(values, self.uncertainty)
        passed = self.scale.passed(values)
        for x, v, m in zip(pts, values, least):
            run.consider(x, v, float(m))
        if not passed.any():
            return True, conflicts_on_grid(self.criteria, self._names, pts, values)
        run.budget = run.count + self.model.budget
        x0 = pts[int(np.argmax(np.where(passed, least, -np.inf)))]
        try:
            minimize(run.scaled, x0 / self._typical, method="Nelder-Mead",
                     bounds=list(zip(self._low / self._typical, self._high / self._typical)),
                     options={"maxfev": 10 ** 6, "xatol": 0.02, "fatol": 1e-3})
        except _Budget:
            pass  # the second budget is spent: the best values so far stand
        return False, []

    def _full(self, free: np.ndarray, picture: CarPicture,
              outlines: dict[tuple[int, ...], np.ndarray] | None = None) -> np.ndarray:
        """All of the reference law's variables: the searched ``free`` ones, clipped, and
        the sub-solved ones as their solves set them."""
        x = np.zeros(len(self._free))
        x[self._free] = free
        x = self.reference.clip(x)
        if self._solves:
            p = self.reference.correction_at(x).params
            solved = self._solved(p, picture, {} if outlines is None else outlines)
            names = self.reference.variables
            platform = self.reference.platform
            for i, n in enumerate(names):
                if not self._free[i]:
                    x[i] = getattr(solved, n) - getattr(platform, n)
            x = self.reference.clip(x)
        return x

    def params_at(self, free: np.ndarray, picture: CarPicture,
                  outlines: dict[tuple[int, ...], np.ndarray] | None = None) -> IspParams:
        """The car's setting at the searched variables ``free`` (sub-solves applied;
        ``outlines``: the picture's outline points by labels, kept between calls)."""
        return self.reference.correction_at(self._full(free, picture, outlines)).params

    def _solved(self, params: IspParams, picture: CarPicture,
                outlines: dict[tuple[int, ...], np.ndarray]) -> IspParams:
        """``params`` with each sub-solved parameter set by its EC's solve on the picture's
        outline of the EC's labels (left as is where the object is not seen)."""
        scale = picture.input_scale
        at = params if scale == 1.0 else params.for_input_scale(scale)
        size = (picture.fisheye.shape[1], picture.fisheye.shape[0])
        current = params
        for ec, hook, target in self._solves:
            if hook.labels not in outlines:
                outlines[hook.labels] = outline_points(picture.fisheye, hook.labels)
            pts = outlines[hook.labels]
            if len(pts) < 3:
                continue
            xy, ok = input_to_plane(at.replace(**{hook.param: getattr(current, hook.param)}),
                                    pts, size)
            if np.count_nonzero(ok) < 3:
                continue
            value = checked_solve_value(ec, "solve", call_ec(
                ec, "sub-solve", "a car's plane points", hook.solve, xy[ok], current,
                self.output, target))
            if value is not None:
                current = current.replace(**{hook.param: float(value)})
        return current


def _written_solves(criteria: Criteria, reference: CompensationLaw
                    ) -> list[tuple[EcDefinition, SubSolve, float]]:
    """(EC, its sub-solve, target) for each enabled EC whose sub-solve pins a parameter the
    model writes (not the pans or tilt: they turn the view, which no solve sets)."""
    written = set(reference.variables) - {"pan_x", "pan_y", "tilt"}
    out: list[tuple[EcDefinition, SubSolve, float]] = []
    taken: set[str] = set()
    for ec, hook, target in criteria.sub_solves(written):
        if hook.param not in taken:  # the first EC that pins a parameter sets it
            taken.add(hook.param)
            out.append((ec, hook, target))
    return sorted(out, key=lambda t: t[1].order)


class _Run:
    """One car's search: every evaluation counted against the budget, the best kept."""

    def __init__(self, law: EcSolveLaw, picture: CarPicture):
        self.law = law
        self.picture = picture
        self.count = 0
        self.budget = law.model.budget
        self.best_x = np.zeros(len(law.variables))
        self.best_least = -math.inf
        self.best_values = np.full(len(law.criteria.ids), np.nan)
        self.best_passed = False
        self._seen: dict[bytes, float] = {}
        #: The picture's outline points by labels (the sub-solves read them).
        self.outlines: dict[tuple[int, ...], np.ndarray] = {}

    def consider(self, x: np.ndarray, values: np.ndarray, least: float) -> None:
        """Keep ``x`` if it is the best so far (a tie keeps the earlier: smaller change)."""
        if least > self.best_least:
            self.best_x, self.best_least = np.array(x, np.float64), least
            self.best_values = np.asarray(values, np.float64)
            self.best_passed = bool(self.law.scale.passed(values)[0])

    def value(self, x: np.ndarray) -> float:
        """The least margin at searched variables ``x`` (clipped; evaluated once)."""
        law = self.law
        x = np.clip(np.asarray(x, np.float64), law._low, law._high)
        key = np.round(x / law._typical, 9).tobytes()
        if key in self._seen:
            return self._seen[key]
        if self.count >= self.budget:
            raise _Budget
        values = self.picture.values([law.params_at(x, self.picture, self.outlines)])[0]
        self.count += 1
        least = float(law.scale.least(values, law.uncertainty)[0])
        self._seen[key] = least
        self.consider(x, values, least)
        if law.settled(values):
            raise _Budget
        return least

    def scaled(self, z: np.ndarray) -> float:
        """Nelder–Mead's objective: minus the least margin at scaled variables ``z``."""
        m = self.value(np.asarray(z) * self.law._typical)
        return -m if math.isfinite(m) else -1e6
