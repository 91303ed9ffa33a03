"""The Kannala-Brandt lens, exactly as ``cv2.fisheye`` defines it.

    θ_d = θ · (1 + k1·θ² + k2·θ⁴ + k3·θ⁶ + k4·θ⁸)

with θ the incidence angle and θ_d the distorted angle, both radians.  ``k = 0`` is the
equidistance lens (:mod:`.equidistance`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Sequence

import numpy as np

from .lens import LensModel, newton_undistort, register_lens_model

__all__ = ["KannalaBrandt", "distort_theta", "distort_theta_derivative", "undistort_theta"]


def distort_theta(theta: np.ndarray, k: np.ndarray | Sequence[float]) -> np.ndarray:
    """Distorted angle θ_d = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ + k4θ⁸), radians in and out."""
    t2 = theta * theta
    return theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))))


def distort_theta_derivative(theta: np.ndarray, k: np.ndarray | Sequence[float]) -> np.ndarray:
    """dθ_d/dθ = 1 + 3k1θ² + 5k2θ⁴ + 7k3θ⁶ + 9k4θ⁸ (θ in radians)."""
    t2 = theta * theta
    return 1.0 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])))


def undistort_theta(
    theta_d: np.ndarray, k: np.ndarray | Sequence[float], *, theta_max: float
) -> np.ndarray:
    """Invert :func:`distort_theta` on [0, theta_max] by Newton's method.

    Parameters
    ----------
    theta_d : ndarray
        Distorted angles (radians, ≥ 0).
    k : (4,) float
        Kannala-Brandt coefficients k1..k4.
    theta_max : float
        Largest incidence angle of interest (radians); the polynomial must be increasing on
        [0, theta_max] (checked when the camera is built).

    Returns
    -------
    theta : ndarray
        Incidence angles (radians).  Values of ``theta_d`` beyond the lens's range give
        ``theta_max * 1.5`` (> ``theta_max``), so callers can mask them.
    """
    theta_d = np.asarray(theta_d, dtype=np.float64)
    if not np.any(k):
        return theta_d.copy()
    return newton_undistort(lambda t: distort_theta(t, k), lambda t: distort_theta_derivative(t, k),
                            theta_d, theta_max)


@dataclass(frozen=True)
class KannalaBrandt(LensModel):
    """The Kannala-Brandt lens with coefficients ``k`` = (k1, k2, k3, k4).  Angles in radians."""

    name: ClassVar[str] = "kannala_brandt"
    k: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    def distort(self, theta: np.ndarray) -> np.ndarray:
        """θ_d (radians) of incidence angles θ (radians); see :func:`distort_theta`."""
        return distort_theta(theta, np.asarray(self.k))

    def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
        """dθ_d/dθ at θ (radians); see :func:`distort_theta_derivative`."""
        return distort_theta_derivative(theta, np.asarray(self.k))

    def undistort(self, theta_d: np.ndarray, *, theta_max: float) -> np.ndarray:
        """θ (radians) of θ_d (radians); see :func:`undistort_theta`."""
        return undistort_theta(theta_d, np.asarray(self.k), theta_max=theta_max)


def _kannala_brandt(k: Sequence[float] | None) -> KannalaBrandt:
    if k is None:
        raise ValueError("model kannala_brandt needs k: [k1, k2, k3, k4]")
    k1, k2, k3, k4 = (float(x) for x in k)
    return KannalaBrandt((k1, k2, k3, k4))


register_lens_model(KannalaBrandt.name, _kannala_brandt)
