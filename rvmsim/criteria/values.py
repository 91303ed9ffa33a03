"""One EC's scored outcome (:class:`EcValue`), on its own so that the registry, scoring and
annotation can all name it without importing each other."""

from __future__ import annotations

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

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: id, name, value, unit, range, score, passed, enabled."""
        return {
            "id": self.id, "name": self.name, "value": self.value, "unit": self.unit,
            "range": [self.low, self.high], "score": self.score, "passed": self.passed,
            "enabled": self.enabled,
        }
