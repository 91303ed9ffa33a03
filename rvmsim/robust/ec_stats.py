"""Each EC over a robustness run's samples: failure rate, worst value and margin, the axes
driving its failures and its value as a formula of the offsets and load."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..criteria import Criteria, EcBatch
from .samples import MountSample
from .sensitivity import Sensitivity, fit_sensitivity, sensitivity_axes
from .stats import AxisEffect, ec_margins, failure_drivers
from .variation import MOUNT_AXES, Variation

__all__ = ["EcStats", "ec_stats", "driver_text"]


@dataclass(frozen=True)
class EcStats:
    """One EC over the samples: failure rate, worst value and margin (signed distance to
    the nearer end of the range, EC unit; < 0 fails), the margins (histograms), the axes
    driving its failures (strongest first; :func:`~rvmsim.robust.stats.failure_drivers`)
    and its value as a formula of the offsets and load
    (:func:`~rvmsim.robust.sensitivity.fit_sensitivity`; None: too few measured)."""

    id: str
    name: str
    unit: str
    low: float | None
    high: float | None
    enabled: bool
    n_fail: int
    failure_rate: float
    worst_value: float | None
    worst_margin: float | None
    worst_sample: int
    margins: tuple[float, ...]
    drivers: tuple[AxisEffect, ...] = ()
    sensitivity: Sensitivity | None = None

    @property
    def driver(self) -> AxisEffect | None:
        """The axis driving the failures (None when the EC never fails, or fails alike
        whatever every axis's value, e.g. on every sample)."""
        top = self.drivers[0] if self.n_fail and self.drivers else None
        return top if top is not None and top.spread > 0 else None

    def as_dict(self) -> dict[str, Any]:
        d = self.driver
        return {"id": self.id, "name": self.name, "unit": self.unit,
                "range": [self.low, self.high], "enabled": self.enabled,
                "n_fail": self.n_fail, "failure_rate": self.failure_rate,
                "worst_value": self.worst_value, "worst_margin": self.worst_margin,
                "worst_sample": self.worst_sample,
                "driver": None if d is None else d.describe(),
                "axes": [e.as_dict() for e in self.drivers],
                "sensitivity": None if self.sensitivity is None else self.sensitivity.as_dict()}


def driver_text(e: EcStats, n: int) -> str:
    """``; 2-3 ≈ |16.0·yaw + 16.5·roll| px, R² 0.99 (terciles: roll_deg …)``."""
    d = e.driver
    terciles = (d.describe() if d is not None else
                "on every sample: no axis drives it" if e.n_fail == n else "")
    if e.sensitivity is None:
        return f"; driven by {terciles}" if d is not None else (
            f"; {terciles}" if terciles else "")
    return f"; {e.sensitivity.describe()}" + (f" (terciles: {terciles})" if terciles else "")


def ec_stats(crit: Criteria, samples: Sequence[MountSample], ev: EcBatch,
              variation: Variation) -> tuple[EcStats, ...]:
    axes = {n: np.array([s.offsets[i] for s in samples])
            for i, n in enumerate(MOUNT_AXES) if variation.axes[i].varies}
    loads = np.array([s.load.name for s in samples])
    seen = sensitivity_axes(samples, variation)
    states = [s.name for s in variation.load_states]
    out = []
    for j, d in enumerate(crit.ecs):
        c = crit.items[d.id]
        margins = ec_margins(ev.values[:, j], c.low, c.high)
        failed = ~ev.passed[:, j]
        finite = np.where(np.isnan(margins), np.inf, margins)
        w = int(np.argmin(finite)) if np.isfinite(finite).any() else int(np.argmax(failed))
        worst_value = ev.values[w, j]
        out.append(EcStats(
            d.id, d.name, d.unit, c.low, c.high, c.enabled, int(failed.sum()),
            float(failed.mean()), None if np.isnan(worst_value) else float(worst_value),
            None if np.isnan(margins[w]) else float(margins[w]), w,
            tuple(float(m) for m in margins),
            tuple(failure_drivers(failed, axes, loads)) if failed.any() else (),
            fit_sensitivity(ev.values[:, j], seen, loads, states=states, ec_id=d.id,
                            unit=d.unit)))
    return tuple(out)


