"""The bidirectional sigmoid of the paper's equation (4), and one EC's acceptance settings.

An EC's measured value gets a score in [0, 1] from its :class:`Sigmoid` and passes or fails
its acceptable range; :class:`Criterion` holds both (and whether the EC counts) for one EC.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Sigmoid", "Criterion"]


# ---------------------------------------------------------------------------- sigmoids
def _logistic(z: float) -> float:
    # 1 / (1 + e^-z), without overflow for large |z|
    return 0.5 * (1.0 + math.tanh(0.5 * z))


@dataclass(frozen=True)
class Sigmoid:
    """The bidirectional sigmoid of the paper's equation (4).

    ``f(x) = 1/(1 + e^(−c1·(x − c2))) · 1/(1 + e^(c3·(x − c4)))``; c2 and c4 are the lower
    and upper thresholds (``-inf`` / ``inf`` for a one-sided criterion), c1 and c3 the slopes.
    """

    c1: float = 1.0
    c2: float = -math.inf
    c3: float = 1.0
    c4: float = math.inf

    def __post_init__(self) -> None:
        for key in ("c1", "c2", "c3", "c4"):
            object.__setattr__(self, key, float(getattr(self, key)))
        if self.c1 < 0 or self.c3 < 0:
            raise ValueError("sigmoid slopes c1, c3 must be >= 0")
        if math.isnan(self.c2) or math.isnan(self.c4) or self.c2 > self.c4:
            raise ValueError("sigmoid thresholds need c2 <= c4")

    def __call__(self, x: float) -> float:
        lower = 1.0 if self.c2 == -math.inf else _logistic(self.c1 * (x - self.c2))
        upper = 1.0 if self.c4 == math.inf else _logistic(-self.c3 * (x - self.c4))
        return lower * upper

    @classmethod
    def from_range(cls, low: float | None, high: float | None, tolerance: float) -> Sigmoid:
        """Coefficients from an acceptable range and a tolerance (paper's future work 1–2).

        Each side scores 0.95 at the range's edge and 0.05 at ``tolerance`` beyond it: the
        threshold sits ``tolerance/2`` outside the edge and the slope is 2·ln(19)/tolerance.
        """
        if tolerance <= 0:
            raise ValueError("tolerance must be > 0")
        slope = 2.0 * math.log(19.0) / tolerance
        return cls(
            c1=slope if low is not None else 0.0,
            c2=low - tolerance / 2 if low is not None else -math.inf,
            c3=slope if high is not None else 0.0,
            c4=high + tolerance / 2 if high is not None else math.inf,
        )


# ---------------------------------------------------------------------------- criteria
@dataclass(frozen=True)
class Criterion:
    """One EC's acceptable range (pass/fail), its sigmoid (score) and whether it counts."""

    id: str
    low: float | None = None
    high: float | None = None
    sigmoid: Sigmoid | None = None  # None: binary, the score is the 0/1 measurement
    enabled: bool = True

    def passes(self, value: float | None) -> bool:
        """Whether ``value`` lies in the acceptable range (a binary EC without a range: is
        1); ``None`` (not measured) fails."""
        if value is None:
            return False
        if self.sigmoid is None and self.low is None and self.high is None:
            return value >= 1.0
        return (self.low is None or value >= self.low) and (self.high is None or value <= self.high)

    def score(self, value: float | None) -> float:
        """The sigmoid score in [0, 1] (a binary EC: its 0/1 value); ``None`` scores 0."""
        if value is None:
            return 0.0
        if self.sigmoid is None:
            return 1.0 if value >= 1.0 else 0.0
        return self.sigmoid(value)
