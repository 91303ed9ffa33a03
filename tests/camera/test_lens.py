"""The lens-model interface: a model written against it (here a stereographic lens, which
rvmsim does not ship) gets a working inverse from the shared Newton solver."""

from __future__ import annotations

import numpy as np

from rvmsim.camera import LensModel, newton_undistort


class Stereographic(LensModel):
    """θ_d = 2·tan(θ / 2)."""

    name = "stereographic"

    def distort(self, theta: np.ndarray) -> np.ndarray:
        return 2.0 * np.tan(theta / 2.0)

    def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
        return 1.0 / np.cos(theta / 2.0) ** 2

    def undistort(self, theta_d: np.ndarray, *, theta_max: float) -> np.ndarray:
        return newton_undistort(self.distort, self.distort_derivative, theta_d, theta_max)


def test_newton_inverts_a_new_model_and_flags_out_of_range():
    lens = Stereographic()
    theta = np.linspace(0.0, 1.6, 400)
    np.testing.assert_allclose(lens.undistort(lens.distort(theta), theta_max=1.65), theta,
                               atol=1e-10)
    np.testing.assert_allclose(lens.undistort(np.array([1.0]), theta_max=1.65),
                               2 * np.arctan(0.5), atol=1e-12)
    # 2·tan(1.65·1.5 / 2) ≈ 5.2: θ_d = 50 lies beyond the lens's reach on [0, 1.5·θ_max]
    assert lens.undistort(np.array([50.0]), theta_max=1.65)[0] > 1.65


def test_monotonic_check_uses_the_derivative():
    class Folding(Stereographic):
        def distort_derivative(self, theta: np.ndarray) -> np.ndarray:
            return np.cos(theta)  # ≤ 0 from 90°

    assert Stereographic().is_monotonic(2.0)
    assert Folding().is_monotonic(1.5) and not Folding().is_monotonic(1.6)
