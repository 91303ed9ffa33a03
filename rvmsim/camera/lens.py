"""The lens-model interface: how a lens bends a ray's incidence angle.

A radial lens model maps the incidence angle θ of a ray (radians, from the optical axis) to
the distorted angle θ_d (radians): the ray lands at ``f · θ_d`` px from the principal point,
in the direction of its azimuth (see :class:`~rvmsim.camera.FisheyeCamera`).  Each model is
its own module (:mod:`.equidistance`, :mod:`.kannala_brandt`) and registers under its name
(:func:`register_lens_model`); a new one subclasses :class:`LensModel` and registers too
(docs/extending.md).

Convention
----------
θ and θ_d are radians, θ ≥ 0.  ``distort`` must be increasing on the lens's field
[0, θ_max] (else the image folds); :meth:`LensModel.is_monotonic` checks it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Callable, ClassVar, Optional

import numpy as np

__all__ = ["LensModel", "newton_undistort", "LENS_MODELS", "LensFactory", "register_lens_model",
           "make_lens"]


class LensModel(ABC):
    """A radial lens: θ → θ_d, its derivative, and the inverse θ_d → θ."""

    #: Name of the model as scene files spell it (``lens.model``).
    name: ClassVar[str]

    @abstractmethod
    def distort(self, theta: np.ndarray) -> np.ndarray:
        """Distorted angles θ_d (radians) of incidence angles ``theta`` (radians)."""

    @abstractmethod
    def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
        """dθ_d/dθ (dimensionless) at incidence angles ``theta`` (radians)."""

    @abstractmethod
    def undistort(self, theta_d: np.ndarray, *, theta_max: float) -> np.ndarray:
        """Incidence angles θ (radians) of distorted angles ``theta_d`` (radians, ≥ 0).

        Values of ``theta_d`` beyond what the lens reaches on [0, ``theta_max``] give
        ``theta_max * 1.5`` (> ``theta_max``), so callers can mask them.
        """

    def is_monotonic(self, theta_max: float, samples: int = 2048) -> bool:
        """Whether θ_d increases strictly over [0, ``theta_max``] (radians), checked on
        ``samples`` evenly spaced angles."""
        theta = np.linspace(0.0, theta_max, samples)
        return not bool(np.any(self.distort_derivative(theta) <= 0))


def newton_undistort(
    distort: Callable[[np.ndarray], np.ndarray],
    derivative: Callable[[np.ndarray], np.ndarray],
    theta_d: np.ndarray,
    theta_max: float,
) -> np.ndarray:
    """Invert a lens's ``distort`` on [0, theta_max] by Newton's method.

    Parameters
    ----------
    distort, derivative : callable
        θ → θ_d and θ → dθ_d/dθ (radians in, radians / dimensionless out).
    theta_d : ndarray
        Distorted angles (radians, ≥ 0), float64.
    theta_max : float
        Largest incidence angle of interest (radians); ``distort`` must be increasing on
        [0, theta_max].

    Returns
    -------
    theta : ndarray
        Incidence angles (radians).  Values of ``theta_d`` beyond the lens's range give
        ``theta_max * 1.5`` (> ``theta_max``), so callers can mask them.
    """
    theta = theta_d.copy()
    limit = theta_max * 1.5
    for _ in range(20):
        f = distort(theta) - theta_d
        df = derivative(theta)
        df = np.where(np.abs(df) < 1e-6, 1e-6, df)
        step = f / df
        theta = np.clip(theta - step, 0.0, limit)
        if np.max(np.abs(step), initial=0.0) < 1e-12:
            break
    # Where θ_d lies beyond what the lens reaches, Newton lands on a wrong root (or 0):
    # report those as out of range.
    bad = np.abs(distort(theta) - theta_d) > 1e-9 * np.maximum(1.0, theta_d)
    return np.where(bad, limit, theta)


# ---------------------------------------------------------------------------- registry
#: Builds a lens from the camera's coefficients ``k`` (None: none given); raises ValueError
#: with a one-line reason when the coefficients do not fit the model.
LensFactory = Callable[[Optional[Sequence[float]]], LensModel]

#: Every lens model by the name scene files give it (``camera.lens.model``), in
#: registration order: ``equidistance`` (the paper's, and the ISP's own lens) and
#: ``kannala_brandt`` (cv2.fisheye's).  :func:`register_lens_model` adds one.
LENS_MODELS: dict[str, LensFactory] = {}


def register_lens_model(name: str, factory: LensFactory) -> LensFactory:
    """Add a lens model under ``name`` (new; letters, digits and ``_``): a scene's
    ``camera.lens.model: NAME`` then builds its lens with ``factory(k)``.

    Raises
    ------
    ValueError
        ``name`` is empty, malformed or taken.
    """
    if not name or not name.replace("_", "").isalnum() or name in LENS_MODELS:
        raise ValueError(f"lens model name {name!r} is empty, malformed or taken")
    LENS_MODELS[name] = factory
    return factory


def make_lens(name: str, k: Sequence[float] | None) -> LensModel:
    """The lens model ``name`` (:data:`LENS_MODELS`) with coefficients ``k``.

    Raises
    ------
    ValueError
        An unknown model, or coefficients the model does not take (one line).
    """
    factory = LENS_MODELS.get(name)
    if factory is None:
        raise ValueError(f"unknown lens model {name!r} (known: {', '.join(LENS_MODELS)})")
    return factory(k)
