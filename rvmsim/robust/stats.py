"""Yield statistics: the share of samples passing with a 95 % confidence interval, EC
margins, and which tolerance axis drives an EC's failures.

Yield interval: Wilson's score interval.  It keeps close to its nominal coverage for the
sample sizes used here (tens to hundreds) and, unlike the normal approximation, does not
collapse to zero width at a yield of 0 or 100 % (200 passes of 200 give [98.1 %, 100 %]);
Clopper-Pearson's exact interval is wider (more conservative) for the same data.

Failure drivers: for each tolerance axis the samples are split into terciles of the axis's
drawn value (low / middle / high third) and the EC's failure rate is taken in each; the axis
whose terciles differ most (largest max − min failure rate) drives the failures, and the
tercile pattern says how (high: the failures come with large positive offsets; low and
high: with large offsets of either sign, as a symmetric EC such as a left/right difference
shows).  Terciles make no assumption of monotonicity (a rank correlation would miss the
symmetric case) and are stable with a few hundred samples.  Load states are an axis too,
by state.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, TypeVar

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["YieldEstimate", "yield_estimate", "wilson_interval", "AxisEffect", "failure_drivers",
           "ec_margins", "limiting_ec", "limiting_dict"]

#: Two-sided 95 % normal quantile.
_Z95 = 1.959963984540054


class _EcFailures(Protocol):
    """What :func:`limiting_ec` reads of an EC over the samples
    (:class:`~rvmsim.robust.EcStats`)."""

    @property
    def id(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def enabled(self) -> bool: ...
    @property
    def n_fail(self) -> int: ...
    @property
    def failure_rate(self) -> float: ...
    @property
    def worst_margin(self) -> float | None: ...


_E = TypeVar("_E", bound=_EcFailures)


def limiting_ec(ecs: Sequence[_E]) -> _E | None:
    """The *limiting* EC over the samples: the enabled EC that fails on most samples (ties:
    the least worst margin); None when no EC fails.  What a yield is short of first (the
    *binding* EC of one picture is another thing: the least score,
    :func:`rvmsim.markets.binding_ec`)."""
    failing = [e for e in ecs if e.enabled and e.n_fail]
    if not failing:
        return None
    return max(failing, key=lambda e: (e.n_fail, -(e.worst_margin or 0.0)))


def limiting_dict(ecs: Sequence[_EcFailures]) -> dict[str, Any] | None:
    """robustness.json's ``limiting``: the limiting EC's id, name and failures."""
    e = limiting_ec(ecs)
    return None if e is None else {"id": e.id, "name": e.name, "n_fail": e.n_fail,
                                   "failure_rate": e.failure_rate}


def wilson_interval(n_pass: int, n: int, z: float = _Z95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion ``n_pass / n`` (``z``: the normal
    quantile of the confidence, 1.96 for 95 %); (0, 1) when ``n`` is 0."""
    if n <= 0:
        return 0.0, 1.0
    p = n_pass / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True)
class YieldEstimate:
    """The share of samples passing: ``yield_`` (0–1), its 95 % Wilson interval ``ci``,
    ``n_pass`` of ``n``."""

    yield_: float
    ci: tuple[float, float]
    n_pass: int
    n: int

    def as_dict(self) -> dict[str, object]:
        return {"yield": self.yield_, "ci95": list(self.ci), "n_pass": self.n_pass,
                "n": self.n, "interval": "Wilson score"}


class YieldVerdict:
    """What a robustness result says of its yield, from its ``estimate`` and ``min_yield``
    (a mixin of :class:`~rvmsim.robust.RobustnessResult` and
    :class:`~rvmsim.robust.MarketsRobustness`)."""

    min_yield: float | None

    if TYPE_CHECKING:  # a field of one, a property of the other
        @property
        def estimate(self) -> YieldEstimate: ...

    @property
    def yield_(self) -> float:
        return self.estimate.yield_

    @property
    def ci(self) -> tuple[float, float]:
        return self.estimate.ci

    @property
    def meets_min_yield(self) -> bool:
        """Whether the yield reaches ``min_yield`` (or none was given)."""
        return self.min_yield is None or self.yield_ >= self.min_yield


def yield_estimate(passed: np.ndarray) -> YieldEstimate:
    """Yield and 95 % interval from per-sample pass flags ((n,) bool: every enabled EC
    passes)."""
    flags = np.asarray(passed, dtype=bool).ravel()
    n, k = int(flags.size), int(flags.sum())
    return YieldEstimate(k / n if n else 0.0, wilson_interval(k, n), k, n)


def ec_margins(values: np.ndarray, low: float | None, high: float | None) -> np.ndarray:
    """Signed distance of each value to the nearer end of ``[low, high]``, in the EC's unit:
    > 0 inside, < 0 outside; NaN where not measured or the EC has no range."""
    v = np.asarray(values, dtype=np.float64)
    if low is None and high is None:
        return np.full(v.shape, np.nan)
    lo = v - low if low is not None else np.full(v.shape, np.inf)
    hi = high - v if high is not None else np.full(v.shape, np.inf)
    return np.minimum(lo, hi)


@dataclass(frozen=True)
class AxisEffect:
    """One axis's failure rates by tercile (``low``, ``mid``, ``high``; by state for the
    load axis, in ``states`` order) and their spread (max − min)."""

    axis: str
    rates: tuple[float, ...]
    spread: float
    states: tuple[str, ...] = ("low", "mid", "high")

    def describe(self) -> str:
        """``yaw_deg (fails at low and high: 40 % / 0 % / 38 %)``."""
        top = max(self.rates)
        where = [s for s, r in zip(self.states, self.rates) if r >= 0.5 * top and r > 0]
        rates = " / ".join(f"{100 * r:.0f} %" for r in self.rates)
        if len(where) == len(self.states) and len(where) > 1:  # no tercile is clear
            worst = self.states[self.rates.index(top)]
            return f"{self.axis} (fails throughout, most at {worst}: {rates})"
        return f"{self.axis} (fails at {' and '.join(where)}: {rates})"

    def as_dict(self) -> dict[str, object]:
        return {"axis": self.axis, "states": list(self.states), "failure_rates": list(self.rates),
                "spread": self.spread}


def _terciles(x: np.ndarray) -> np.ndarray:
    """Tercile index (0, 1, 2) of each value by rank (ties in rank order)."""
    order = np.argsort(x, kind="stable")
    t = np.empty(x.size, np.intp)
    t[order] = np.minimum(np.arange(x.size) * 3 // max(x.size, 1), 2)
    return t


def failure_drivers(failed: np.ndarray, axes: dict[str, np.ndarray],
                    loads: np.ndarray | None = None) -> list[AxisEffect]:
    """Every varying axis's effect on an EC's failures, the strongest first.

    Parameters
    ----------
    failed : (n,) bool
        Where the EC fails.
    axes : dict
        Axis name → (n,) drawn values (only axes that vary).
    loads : (n,) str, optional
        Each sample's load state (an axis when there are several states).
    """
    f = np.asarray(failed, dtype=bool)
    out: list[AxisEffect] = []
    for name, values in axes.items():
        t = _terciles(np.asarray(values, dtype=np.float64))
        rates = tuple(float(f[t == k].mean()) if np.any(t == k) else 0.0 for k in range(3))
        out.append(AxisEffect(name, rates, max(rates) - min(rates)))
    if loads is not None:
        states = tuple(dict.fromkeys(str(s) for s in loads))
        if len(states) > 1:
            rates = tuple(float(f[loads == s].mean()) for s in states)
            out.append(AxisEffect("load", rates, max(rates) - min(rates), states))
    return sorted(out, key=lambda e: -e.spread)
