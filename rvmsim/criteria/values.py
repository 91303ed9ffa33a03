"""One EC's scored outcome (:class:`EcValue`), on its own so that the registry, scoring and
annotation can all name it without importing each other."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["EcValue"]


@dataclass(frozen=True)
class EcValue:
    """One EC's outcome: its value (``None``: not measured) in ``unit``, its acceptable
    range, score in [0, 1], pass/fail and whether it counts."""

    id: str
    name: str
    value: float | None
    unit: str
    low: float | None
    high: float | None
    score: float
    passed: bool
    enabled: bool

    @property
    def margin(self) -> float | None:
        """Signed distance of the value inside its acceptable range, in the EC's unit:
        > 0 inside, < 0 outside, 0 on a limit; for a two-sided range the distance to the
        nearer limit (as :func:`rvmsim.robust.ec_margins`).  None when not measured or the
        range is open on both sides."""
        if self.value is None or (self.low is None and self.high is None):
            return None
        return min(self.value - self.low if self.low is not None else math.inf,
                   self.high - self.value if self.high is not None else math.inf)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: id, name, value, unit, range, score, passed, enabled."""
        return {
            "id": self.id, "name": self.name, "value": self.value, "unit": self.unit,
            "range": [self.low, self.high], "score": self.score, "passed": self.passed,
            "enabled": self.enabled,
        }
