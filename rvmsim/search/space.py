"""The search space: the tuned ISP parameters, their ranges and coarse grids (paper, section VI).

A :class:`SearchSpace` maps a vector of tuned values (one per :class:`ParamRange`, in order)
to a full :class:`~rvmsim.isp.IspParams` (the untuned parameters at ``base``);
:func:`default_space` fits the paper's nine tuned parameters to a camera.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Iterator, Sequence

import numpy as np

from ..camera import FisheyeCamera
from ..isp import PARAM_SPECS, TUNED_BY_DEFAULT, IspParams

__all__ = ["ParamRange", "SearchSpace", "default_space"]

_SPEC = {s.name: s for s in PARAM_SPECS}


@dataclass(frozen=True)
class ParamRange:
    """One tuned parameter: initial value, search range, coarse grid step and grid points.

    The coarse grid takes ``points`` values ``init + k·step`` centred on ``init``
    (k = −(points − 1)/2 … (points − 1)/2), dropping any outside [low, high]; the range also
    bounds the fine stage and the other strategies.
    """

    name: str
    init: float
    low: float
    high: float
    step: float
    points: int = 3

    def __post_init__(self) -> None:
        spec = _SPEC.get(self.name)
        if spec is None:
            raise ValueError(f"{self.name}: not an ISP parameter")
        if not spec.low <= self.low <= self.init <= self.high <= spec.high:
            raise ValueError(f"{self.name}: need {spec.low:g} <= low <= init <= high <= "
                             f"{spec.high:g}, got {self.low:g}, {self.init:g}, {self.high:g}")
        if self.step <= 0:
            raise ValueError(f"{self.name}: step must be > 0")
        if self.points < 1:
            raise ValueError(f"{self.name}: points must be >= 1")

    def grid(self) -> np.ndarray:
        """The coarse grid values of this parameter, ascending."""
        k = np.arange(self.points) - (self.points - 1) / 2.0
        values = self.init + self.step * k
        keep = (values >= self.low - 1e-9) & (values <= self.high + 1e-9)
        return np.clip(values[keep], self.low, self.high)


@dataclass(frozen=True)
class SearchSpace:
    """The tuned parameters and the values of the others."""

    ranges: tuple[ParamRange, ...]
    base: IspParams = field(default_factory=IspParams)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.ranges)

    @property
    def low(self) -> np.ndarray:
        return np.array([r.low for r in self.ranges])

    @property
    def high(self) -> np.ndarray:
        return np.array([r.high for r in self.ranges])

    @property
    def step(self) -> np.ndarray:
        return np.array([r.step for r in self.ranges])

    def params(self, x: Sequence[float] | np.ndarray) -> IspParams:
        """ISP parameters for a vector of tuned values (clipped to the ranges)."""
        v = np.clip(np.asarray(x, dtype=np.float64), self.low, self.high)
        return self.base.replace(**{n: float(t) for n, t in zip(self.names, v)})

    def vector(self, p: IspParams) -> np.ndarray:
        """The tuned values of ``p``, in ``names`` order."""
        return np.array([getattr(p, n) for n in self.names])

    def grid_size(self) -> int:
        return int(np.prod([len(r.grid()) for r in self.ranges]))

    def grid(self) -> Iterator[np.ndarray]:
        """The coarse grid, in a fixed order (last parameter fastest)."""
        for combo in itertools.product(*(r.grid() for r in self.ranges)):
            yield np.array(combo)

    def narrowed(self, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The fine stage's range around a coarse result: one step each way, clipped."""
        return np.maximum(centre - self.step, self.low), np.minimum(centre + self.step, self.high)


def default_space(camera: FisheyeCamera, names: Sequence[str] = TUNED_BY_DEFAULT) -> SearchSpace:
    """The nine parameters the paper tunes, with initial values fitted to the camera.

    RAD starts at the radius the lens gives 180° (fx·π/2, which with FOV 180 makes the ISP's
    lens model the real one for an equidistance lens); H/V shift start at the principal
    point's offset.  Ranges cover views from nearly uncorrected to strongly corrected; the
    coarse grid takes 3 values per parameter (3⁹ = 19,683 candidates).
    """
    rad0 = camera.fx * math.pi / 2
    h0 = camera.cx - (camera.width - 1) / 2
    v0 = camera.cy - (camera.height - 1) / 2
    q = camera.width / 1280.0  # pixel-valued ranges follow the sensor size
    table = {
        "fov": (180.0, 150.0, 210.0, 20.0),
        "rad": (rad0, 0.55 * rad0, 1.45 * rad0, 0.3 * rad0),
        "h_shift": (h0, h0 - 60 * q, h0 + 60 * q, 30 * q),
        "v_shift": (v0, v0 - 160 * q, v0 + 160 * q, 80 * q),
        "zoom": (0.7, 0.25, 1.45, 0.3),
        "adv_h_shift": (0.0, -0.4, 0.4, 0.2),
        "adv_v_shift": (0.0, -0.8, 0.8, 0.4),
        "adv_h_scale": (1.0, 0.5, 1.8, 0.3),
        "adv_v_scale": (1.2, 0.6, 2.0, 0.4),
    }
    ranges = []
    for n in names:
        if n in table:
            init, lo, hi, step = table[n]
        else:
            spec = _SPEC[n]
            init, lo, hi, step = spec.default, spec.low, spec.high, (spec.high - spec.low) / 4
        ranges.append(ParamRange(n, init, lo, hi, step))
    return SearchSpace(tuple(ranges))
