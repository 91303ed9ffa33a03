"""One EC's scored outcome (:class:`EcValue`), on its own so that the registry, scoring and
annotation can all name it without importing each other."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

__all__ = ["EcValue", "is_yes_no"]


def is_yes_no(low: float | None, high: float | None) -> bool:
    """Whether an acceptable range is one value (1-1, 2-4: ``[1, 1]``): a yes/no EC, met or
    not, with no margin to show (:meth:`EcValue.margin_text`)."""
    return low is not None and low == high


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

    @property
    def yes_no(self) -> bool:
        """A yes/no EC (:func:`is_yes_no`): it has no margin to show, only ✓ or ✗
        (:meth:`margin_text`)."""
        return is_yes_no(self.low, self.high)

    def check_mark(self) -> str:
        """✓ passed, ✗ failed, "—" not measured: a yes/no EC's margin cell."""
        return "—" if self.value is None else ("✓" if self.passed else "✗")

    def margin_text(self, unit: str = "") -> str:
        """The margin as every table shows it (report, sign-off, annotation panel, console,
        gallery): ✓/✗ for a yes/no EC, the signed margin with ``unit`` (4 significant
        digits) otherwise, "—" when there is none."""
        if self.yes_no:
            return self.check_mark()
        m = self.margin
        if m is None or not math.isfinite(m):
            return "—"
        return f"{m:+.4g}{unit}"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: id, name, value, unit, range, score, passed, enabled."""
        return {
            "id": self.id, "name": self.name, "value": self.value, "unit": self.unit,
            "range": [self.low, self.high], "score": self.score, "passed": self.passed,
            "enabled": self.enabled,
        }
