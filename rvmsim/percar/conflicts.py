"""Cars no per-car setting can pass: the grid check of the allowed ranges, and the ECs that
conflict there.

When the law's search ends on a setting that fails some EC, the car's picture is judged at
every point of a grid over the allowed ranges (:data:`GRID_LEVELS` levels per searched
variable, the pans' turn within its limit).  No point passing every EC makes the car
*infeasible* (a statement about that grid: the ranges' ends and the search's own points are
among what was tried).  Its reasons name the ECs that cannot pass together:

- an EC that fails at every grid point: ``infeasible car: 2-3 fails over the whole allowed
  range (best 6.2 px at pan_x +0.75°, …)``;
- two ECs that each pass somewhere but never at the same point, split along one variable:
  ``infeasible car: 2-3 needs pan_x ≤ -0.40°, 3-1 needs pan_x ≥ -0.20°``;
- otherwise the ECs failing at the best grid point.

Variables are named as :attr:`rvmsim.compensation.CompensationLaw.variables` names them
(``pan_x``: the view axis turned toward the image's right, ``pan_y``: toward its bottom,
degrees; the others are the ISP parameters' offsets from the platform setting).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np

from ..compensation import CompensationLaw
from ..criteria import Criteria, score_batch
from .margins import MarginScale

__all__ = ["GRID_LEVELS", "grid_of", "conflicts_on_grid"]

#: Grid levels per searched variable (5³ = 125 points for the pans and tilt, less the
#: pans' corners beyond their turn's limit).
GRID_LEVELS = 5

_UNITS = {"pan_x": "°", "pan_y": "°", "tilt": "°", "h_shift": " px", "v_shift": " px"}


def grid_of(reference: CompensationLaw, free: np.ndarray, levels: int = GRID_LEVELS
            ) -> np.ndarray:
    """The grid points over the allowed ranges of the searched variables (``free``: mask
    over ``reference.variables``), (m, n_free); the pans' turn kept within its limit."""
    low, high = reference.bounds
    axes = [np.linspace(lo, hi, levels) for lo, hi, f in zip(low, high, free) if f]
    pts = np.array(list(itertools.product(*axes)), np.float64).reshape(-1, int(free.sum()))
    names = [n for n, f in zip(reference.variables, free) if f]
    if "pan_x" in names and "pan_y" in names:
        i, j = names.index("pan_x"), names.index("pan_y")
        limit = reference.model.range_of("h_pan")[1]
        pts = pts[np.hypot(pts[:, i], pts[:, j]) <= limit * (1 + 1e-9)]
    return pts


def _fmt(name: str, value: float) -> str:
    return f"{value:+.2f}{_UNITS.get(name, '')}"


def conflicts_on_grid(criteria: Criteria, names: Sequence[str], points: np.ndarray,
                      values: np.ndarray) -> list[str]:
    """Why no grid point passes (the module docstring): one line each, at most three.

    Parameters
    ----------
    criteria : Criteria
    names : sequence of str
        The searched variables (the columns of ``points``).
    points : (m, n) float
    values : (m, k) float
        The EC values at each point.
    """
    ids = criteria.ids
    passed = score_batch(values, criteria).passed
    scale = MarginScale.of(criteria)
    enabled = scale.enabled
    least = scale.least(values)
    best = int(np.argmax(least))
    out: list[str] = []
    for j in (int(i) for i in np.flatnonzero(enabled & ~passed.any(axis=0))):
        m = scale.normalized(values)[:, j]
        b = int(np.argmax(m))
        where = ", ".join(f"{n} {_fmt(n, x)}" for n, x in zip(names, points[b]))
        out.append(f"infeasible car: {ids[j]} fails over the whole allowed range (best "
                   f"{_value(criteria, j, values[b, j])} at {where})")
    somewhere = [int(j) for j in np.flatnonzero(enabled) if passed[:, j].any()]
    for a, b in itertools.combinations(somewhere, 2):
        if len(out) >= 3:
            break
        if (passed[:, a] & passed[:, b]).any():
            continue
        split = _split(names, points, passed[:, a], passed[:, b])
        if split is not None:
            n, (ra, rb) = split
            out.append(f"infeasible car: {ids[a]} needs {n} {ra}, {ids[b]} needs {n} {rb}")
        else:
            out.append(f"infeasible car: {ids[a]} and {ids[b]} pass in disjoint parts of the "
                       "allowed ranges")
    if not out:
        failing = [ids[j] for j in np.flatnonzero(enabled & ~passed[best])]
        out.append(f"infeasible car: no setting in the allowed ranges passes every EC "
                   f"(at the best grid point EC {', '.join(failing)} fail)")
    return out[:3]


def _split(names: Sequence[str], points: np.ndarray, pa: np.ndarray, pb: np.ndarray
           ) -> tuple[str, tuple[str, str]] | None:
    """A variable along which the points where one EC passes all lie below those where the
    other passes (the clearest gap first), as texts (``≤ -0.40°``, ``≥ -0.20°``)."""
    found = []
    for i, n in enumerate(names):
        a, b = points[pa, i], points[pb, i]
        if a.max() < b.min():
            found.append((b.min() - a.max(), n, (f"≤ {_fmt(n, a.max())}", f"≥ {_fmt(n, b.min())}")))
        elif b.max() < a.min():
            found.append((a.min() - b.max(), n, (f"≥ {_fmt(n, a.min())}", f"≤ {_fmt(n, b.max())}")))
    if not found:
        return None
    _, n, texts = max(found, key=lambda t: t[0])
    return n, texts


def _value(criteria: Criteria, j: int, v: float) -> str:
    unit = criteria.ecs[j].unit
    return "not measured" if math.isnan(v) else f"{v:.3g}{(' ' + unit) if unit else ''}"
