"""The equidistance lens: θ_d = θ, so a ray lands f·θ px from the principal point.

This is the paper's equation (3), ``r = f·θ``, and the Kannala-Brandt model with
k1 = … = k4 = 0 (:mod:`.kannala_brandt`).
"""

from __future__ import annotations

from dataclasses import dataclass
from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from .lens import LensModel, register_lens_model

__all__ = ["Equidistance"]


@dataclass(frozen=True)
class Equidistance(LensModel):
    """The equidistance (f-θ) lens.  Angles in radians."""

    name: ClassVar[str] = "equidistance"

    def distort(self, theta: np.ndarray) -> np.ndarray:
        """θ_d = θ (a new float64 array), radians."""
        return np.array(theta, dtype=np.float64)

    def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
        """dθ_d/dθ = 1 everywhere."""
        return np.ones_like(np.asarray(theta, dtype=np.float64))

    def undistort(self, theta_d: np.ndarray, *, theta_max: float) -> np.ndarray:
        """θ = θ_d (a new float64 array), radians; the lens reaches every angle."""
        return np.array(theta_d, dtype=np.float64)


def _equidistance(k: Sequence[float] | None) -> Equidistance:
    if k is not None and any(k):
        raise ValueError("model equidistance takes no k (use model: kannala_brandt)")
    return Equidistance()


register_lens_model(Equidistance.name, _equidistance)
