"""EC margins on one scale, so that one car's ECs can be compared: what the per-car law
maximises is the least of them.

An EC's margin is the signed distance of its value to the nearer end of its acceptable range
(> 0 inside, in the EC's unit: px, %, ‰, …).  Margins of different units are made comparable
by the EC's own sigmoid: a margin ``m`` on a side whose slope is ``c`` counts ``c·m`` (the
logit the customer's sigmoid puts there: 1 is where a step of the value changes the score by
about a factor e).  A side without a slope counts the margin in tenths of the range's width
(or of the limit's size for a one-sided range).  A binary EC (a yes/no value) has no margin:
passing it sets no bound on the least margin, failing it counts :data:`FAIL_MARGIN`; so does
a value that cannot be measured.  Disabled ECs do not count.

Convention
----------
Values are (n, k) in :attr:`rvmsim.criteria.Criteria.ids` order, NaN where not measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..criteria import Criteria, score_batch

__all__ = ["MarginScale", "FAIL_MARGIN"]

#: The normalised margin of a failing binary EC or an EC that cannot be measured: worse than
#: any continuous EC's failure by a few pixels.
FAIL_MARGIN = -10.0


def _side_scale(slope: float, limit: float, width: float) -> float:
    """Normalised units per EC unit on one side of a range (1 for an open side)."""
    if not math.isfinite(limit):
        return 1.0
    if slope > 0 and math.isfinite(slope):
        return slope
    if math.isfinite(width) and width > 0:
        return 10.0 / width
    return 10.0 / abs(limit) if limit != 0 else 1.0


@dataclass(frozen=True)
class MarginScale:
    """The margins of one criteria's ECs (see the module docstring); :meth:`of` builds it.

    Attributes
    ----------
    criteria : Criteria
    low, high : (k,) float64
        The ranges' ends (±inf where open).
    scale_low, scale_high : (k,) float64
        Normalised units per EC unit near each end.
    binary : (k,) bool
        ECs without a margin (yes/no, or a range of one value).
    enabled : (k,) bool
    """

    criteria: Criteria
    low: np.ndarray
    high: np.ndarray
    scale_low: np.ndarray
    scale_high: np.ndarray
    binary: np.ndarray
    enabled: np.ndarray

    @classmethod
    def of(cls, criteria: Criteria) -> MarginScale:
        """The scale of ``criteria``'s ECs."""
        lows, highs, s_lo, s_hi, binary, enabled = [], [], [], [], [], []
        for ec in criteria.ids:
            c = criteria.items[ec]
            lo = -math.inf if c.low is None else float(c.low)
            hi = math.inf if c.high is None else float(c.high)
            sig = c.sigmoid
            width = hi - lo
            lows.append(lo)
            highs.append(hi)
            s_lo.append(_side_scale(sig.c1 if sig is not None else 0.0, lo, width))
            s_hi.append(_side_scale(sig.c3 if sig is not None else 0.0, hi, width))
            binary.append(sig is None or lo == hi)
            enabled.append(c.enabled)
        return cls(criteria, np.array(lows), np.array(highs), np.array(s_lo), np.array(s_hi),
                   np.array(binary, bool), np.array(enabled, bool))

    def margins(self, values: np.ndarray) -> np.ndarray:
        """Signed margins in the ECs' own units, (n, k); NaN for binary ECs and values not
        measured."""
        v = np.atleast_2d(np.asarray(values, dtype=np.float64))
        with np.errstate(invalid="ignore"):
            m = np.minimum(v - self.low, self.high - v)
        return np.where(self.binary, np.nan, m)

    def normalized(self, values: np.ndarray, sigma: np.ndarray | None = None) -> np.ndarray:
        """Normalised margins, (n, k): +inf for disabled ECs and passing binary ones,
        :data:`FAIL_MARGIN` for failing binary ones and values not measured.  With
        ``sigma`` ((k,), the ECs' units), the margin left beyond one σ of each."""
        v = np.atleast_2d(np.asarray(values, dtype=np.float64))
        sig = np.zeros(v.shape[1]) if sigma is None else np.asarray(sigma, np.float64)
        with np.errstate(invalid="ignore"):
            m = np.minimum((v - self.low - sig) * self.scale_low,
                           (self.high - sig - v) * self.scale_high)
        passed = score_batch(v, self.criteria).passed
        m = np.where(self.binary, np.where(passed, np.inf, FAIL_MARGIN), m)
        m = np.where(np.isnan(v), FAIL_MARGIN, m)
        return np.where(self.enabled, m, np.inf)

    def least(self, values: np.ndarray, sigma: np.ndarray | None = None) -> np.ndarray:
        """The least normalised margin of each row, (n,): the law's objective (> 0: every
        enabled EC passes, by more than ``sigma`` of it when given; +inf when no EC bounds
        it)."""
        return self.normalized(values, sigma).min(axis=1)

    def passed(self, values: np.ndarray) -> np.ndarray:
        """(n,) bool: every enabled EC passes (:func:`rvmsim.criteria.score_batch`)."""
        return score_batch(np.atleast_2d(np.asarray(values, dtype=np.float64)),
                           self.criteria).all_passed
