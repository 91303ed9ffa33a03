"""The EOL station's measurement: the deviation it reads is the car's plus its error.

The error is normal, independent per axis, with the model's σ (angles in degrees, positions
in mm), drawn from a generator seeded by (seed, car index, tolerance scale): the same car of
the same run always gets the same error, whatever else is drawn.
"""

from __future__ import annotations

import numpy as np

from .law import Deviation
from .model import CompensationModel

__all__ = ["station_error", "measured_deviation"]


def station_error(model: CompensationModel, seed: int, index: int,
                  scale: float = 1.0) -> Deviation:
    """The station's error on car ``index`` of run ``seed`` (zero when both σ are 0)."""
    if model.angle_sigma_deg == 0 and model.position_sigma_mm == 0:
        return Deviation()
    rng = np.random.default_rng([0xE01, int(seed) & 0xFFFFFFFF, int(index) & 0xFFFFFFFF,
                                 int(round(scale * 1000))])
    z = rng.standard_normal(6)
    sigma = np.array([model.position_sigma_mm] * 3 + [model.angle_sigma_deg] * 3)
    return Deviation.from_offsets(z * sigma)


def measured_deviation(true: Deviation, model: CompensationModel, seed: int, index: int,
                       scale: float = 1.0) -> Deviation:
    """What the station reads for a car whose camera deviates by ``true``."""
    return true + station_error(model, seed, index, scale)
