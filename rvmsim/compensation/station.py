"""The EOL station's measurement: the deviation it reads is the car's plus its error, and
the body's edge it finds on the capture is off by the edge finder's error.

The errors are normal, independent per axis, with the model's σ (angles in degrees,
positions in mm, the edge in fisheye px), drawn from generators seeded by (seed, car index,
tolerance scale): the same car of the same run always gets the same errors, whatever else is
drawn.
"""

from __future__ import annotations

import numpy as np

from .law import Deviation
from .model import CompensationModel

__all__ = ["station_error", "measured_deviation", "edge_error"]


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


def edge_error(model: CompensationModel, seed: int, index: int, scale: float = 1.0
               ) -> tuple[float, float]:
    """The edge finder's error on car ``index`` of run ``seed``: the found body edge's
    offset at the image centre and its tilt at the image's sides, fisheye px, each
    N(0, ``edge_sigma_px``) ((0, 0) when the σ is 0)."""
    if model.edge_sigma_px == 0:
        return 0.0, 0.0
    rng = np.random.default_rng([0xED6E, int(seed) & 0xFFFFFFFF, int(index) & 0xFFFFFFFF,
                                 int(round(scale * 1000))])
    d = rng.standard_normal(2) * model.edge_sigma_px
    return float(d[0]), float(d[1])
