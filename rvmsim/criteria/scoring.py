"""A customer's criteria, and scoring measurements with them (one candidate or many).

The EC score is the product of the enabled ECs' sigmoid scores (paper, section V); a
candidate passes when every enabled EC's value lies in its acceptable range.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .groups import LabelGroup, unique_groups
from .hooks import SubSolve
from .measure import Measurements, MeasureOptions, call_ec
from .registry import EcDefinition, builtin_ecs, checked_solve_value
from .sigmoid import Criterion, Sigmoid
from .values import EcValue

if TYPE_CHECKING:
    from ..scene import Display

__all__ = ["Criteria", "EcValue", "EcResult", "EcBatch", "score_batch", "score",
           "values_array"]


@dataclass(frozen=True)
class Criteria:
    """A customer's criteria: the selected ECs in evaluation order, one :class:`Criterion`
    per EC, and the measurement options.

    Parameters
    ----------
    name : str
    items : dict
        EC id → :class:`Criterion`, one per selected EC.
    upper_region_fraction : float
        The top fraction of the image that counts as its upper region (EC 2-4).
    edge_columns : int
        Columns averaged for the bumper heights t_c, t_l, t_r.
    source : str
        Where the criteria came from (a file, ``<default>``).
    ecs : tuple of EcDefinition
        The selected ECs in evaluation order; default: the paper's eleven.
    display : Display, optional
        The criteria file's ``display`` section (a scene's own wins).
    parameters : dict
        EC id → {parameter name: value}: the criteria file's changes to ECs' parameters
        (:attr:`EcDefinition.parameters`).
    """

    name: str
    items: dict[str, Criterion]
    upper_region_fraction: float = 0.5
    edge_columns: int = 4
    source: str = "<default>"
    ecs: tuple[EcDefinition, ...] = ()
    display: Display | None = None
    parameters: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.ecs:
            object.__setattr__(self, "ecs", builtin_ecs())
        ids = [ec.id for ec in self.ecs]
        if len(set(ids)) != len(ids):
            raise ValueError(f"criteria select an EC twice: {ids}")
        if set(self.items) != set(ids):
            raise ValueError(f"criteria must define every selected EC {tuple(ids)}")

    @property
    def ids(self) -> tuple[str, ...]:
        """The ids of the selected ECs in evaluation order (the columns of :class:`EcBatch`
        and of the run store's ``ec`` column)."""
        return tuple(ec.id for ec in self.ecs)

    @functools.cached_property
    def options(self) -> MeasureOptions:
        """The measurement options the ECs receive (each EC's parameters: its defaults with
        :attr:`parameters`' changes)."""
        params = tuple((ec.id, tuple({**dict(ec.parameters), **self.parameters.get(ec.id, {})
                                      }.items())) for ec in self.ecs if ec.parameters)
        return MeasureOptions(self.upper_region_fraction, self.edge_columns, self.display,
                              params)

    @property
    def uses_scene(self) -> bool:
        """Some selected EC reads the scene, its fisheye labels or the ISP map
        (:attr:`EcDefinition.uses_scene`), not only the RVM labels."""
        return any(ec.uses_scene for ec in self.ecs)

    @functools.cached_property
    def groups(self) -> tuple[LabelGroup, ...]:
        """The label groups the selected ECs read, each once."""
        return unique_groups(g for ec in self.ecs for g in ec.groups)

    def sub_solves(self, params: Collection[str]) -> list[tuple[EcDefinition, SubSolve, float]]:
        """(EC, its sub-solve, target) of every selected, enabled EC whose sub-solve sets one
        of ``params`` and whose range has a target (:attr:`SubSolve.target`), in the
        criteria's order (sort by :attr:`SubSolve.order` for the solve order)."""
        found = []
        for ec in self.ecs:
            hook, criterion = ec.sub_solve, self.items[ec.id]
            if hook is None or not criterion.enabled or hook.param not in params:
                continue
            target = checked_solve_value(ec, "target", call_ec(
                ec, "sub-solve target", f"the criterion of {self.source}", hook.target,
                criterion))
            if target is not None:
                found.append((ec, hook, target))
        return found

    @functools.cached_property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """Per EC in :attr:`ids` order, for :func:`score_batch`: low, high (±max float when
        open), binary, pass-flag-only, c1, c2, c3, c4, enabled."""
        items = [self.items[ec] for ec in self.ids]
        big = np.finfo(np.float64).max
        sig = [c.sigmoid or Sigmoid() for c in items]
        return (
            np.array([-big if c.low is None else c.low for c in items]),
            np.array([big if c.high is None else c.high for c in items]),
            np.array([c.sigmoid is None for c in items], bool),
            np.array([c.sigmoid is None and c.low is None and c.high is None for c in items],
                     bool),
            np.array([s.c1 for s in sig]), np.array([s.c2 for s in sig]),
            np.array([s.c3 for s in sig]), np.array([s.c4 for s in sig]),
            np.array([c.enabled for c in items], bool),
        )


@dataclass(frozen=True)
class EcResult:
    """All selected ECs: their values and scores, the EC score (product of the enabled
    scores) and whether every enabled EC passes its acceptable range.

    ``definitions`` are the ECs of ``items`` (same order), for drawing them."""

    items: tuple[EcValue, ...]
    score: float
    passed: bool
    measurements: Measurements
    criteria_name: str = ""
    definitions: tuple[EcDefinition, ...] = ()

    def __getitem__(self, ec: str) -> EcValue:
        for item in self.items:
            if item.id == ec:
                return item
        raise KeyError(ec)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: criteria name, EC score, passed, and every EC (:meth:`EcValue.as_dict`)."""
        return {"criteria": self.criteria_name, "ec_score": self.score, "passed": self.passed,
                "ecs": [i.as_dict() for i in self.items]}

    def table(self) -> str:
        """A plain-text table for terminals."""
        k = max([4, *(len(i.id) for i in self.items)])
        n = max([26, *(len(i.name) for i in self.items)])
        lines = [f"{'EC':{k}} {'measurement':{n}} {'value':>10} {'unit':4} {'range':>15} "
                 f"{'score':>7}  result"]
        for i in self.items:
            val = "—" if i.value is None else f"{i.value:10.3f}"
            rng = f"[{_fmt(i.low)}, {_fmt(i.high)}]"
            res = "off" if not i.enabled else ("pass" if i.passed else "FAIL")
            lines.append(f"{i.id:{k}} {i.name:{n}} {val:>10} {i.unit:4} {rng:>15} "
                         f"{i.score:7.3f}  {res}")
        lines.append(f"EC score {self.score:.4g}  ({'all pass' if self.passed else 'not all pass'})")
        return "\n".join(lines)


def _fmt(x: float | None) -> str:
    return "–" if x is None else f"{x:g}"


@dataclass(frozen=True)
class EcBatch:
    """The ECs of many candidates at once (rows; columns in ``ids`` order, the criteria's
    :attr:`Criteria.ids`): what tuning stores for every candidate, without building an
    :class:`EcResult` per candidate.

    ``values`` is NaN where the measured object is not in the image (``None`` in
    :class:`EcResult`)."""

    values: np.ndarray  # (n, k) float64
    scores: np.ndarray  # (n, k) float64
    passed: np.ndarray  # (n, k) bool
    enabled: np.ndarray  # (k,) bool
    ids: tuple[str, ...] = ()

    @property
    def score(self) -> np.ndarray:
        """EC score per candidate: the product of the enabled ECs' scores, (n,)."""
        return np.prod(np.where(self.enabled, self.scores, 1.0), axis=1)

    @property
    def all_passed(self) -> np.ndarray:
        """Whether every enabled EC passes, (n,) bool."""
        return np.all(self.passed | ~self.enabled, axis=1)

    def objective(self, floor: float) -> np.ndarray:
        """Σ log(max(score_i, floor)) over the enabled ECs, (n,)."""
        return np.sum(np.where(self.enabled, np.log(np.maximum(self.scores, floor)), 0.0), axis=1)


def values_array(m: Measurements, ids: Sequence[str] | None = None) -> np.ndarray:
    """The measured values in ``ids`` order (default: the order measured), NaN for ``None``:
    (k,) float64."""
    keys = m.values.keys() if ids is None else ids
    return np.array([np.nan if m.values.get(ec) is None else m.values[ec] for ec in keys],
                    np.float64)


def score_batch(values: np.ndarray, criteria: Criteria) -> EcBatch:
    """Score many candidates' measurements at once (vectorised :meth:`Criterion.score` and
    :meth:`Criterion.passes`; the tests check they agree).

    Parameters
    ----------
    values : (n, k) float
        Measured values in ``criteria.ids`` order, NaN where not measured.
    criteria : Criteria
    """
    x = np.atleast_2d(np.asarray(values, dtype=np.float64))
    low, high, binary, only_flag, c1, c2, c3, c4, enabled = criteria.arrays
    measured = ~np.isnan(x)
    xs = np.where(measured, x, 0.0)
    with np.errstate(invalid="ignore", over="ignore"):
        # 1/(1 + e^(−z)) = (1 + tanh(z/2))/2, as Sigmoid does; an infinite threshold is 1
        lower = np.where(np.isneginf(c2), 1.0, 0.5 * (1.0 + np.tanh(0.5 * (c1 * (xs - c2)))))
        upper = np.where(np.isposinf(c4), 1.0, 0.5 * (1.0 + np.tanh(0.5 * (-c3 * (xs - c4)))))
    graded = lower * upper
    scores = np.where(measured, np.where(binary, (xs >= 1.0).astype(np.float64), graded), 0.0)
    in_range = (xs >= low) & (xs <= high)
    passed = measured & np.where(only_flag, xs >= 1.0, in_range)
    return EcBatch(x, scores, passed, enabled, criteria.ids)


def score(m: Measurements, criteria: Criteria) -> EcResult:
    """Score measurements with a customer's criteria (one candidate; :func:`score_batch`
    scores many at once, and the tests check that the two agree)."""
    items = []
    total = 1.0
    passed = True
    for d in criteria.ecs:
        c = criteria.items[d.id]
        value = m.values.get(d.id)
        s = float(c.score(value))
        ok = c.passes(value)
        items.append(EcValue(d.id, d.name, value, d.unit, c.low, c.high, s, ok, c.enabled))
        if c.enabled:
            total *= s
            passed &= ok
    return EcResult(tuple(items), total, passed, m, criteria.name, criteria.ecs)
