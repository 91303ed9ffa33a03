"""The equidistance lens: θ_d = θ, the Kannala-Brandt model with k = 0."""

from __future__ import annotations

import numpy as np

from rvmsim.camera import Equidistance, KannalaBrandt


def test_identity_and_same_as_zero_kannala_brandt():
    theta = np.linspace(0, 1.7, 300)
    lens = Equidistance()
    out = lens.distort(theta)
    np.testing.assert_array_equal(out, theta)
    assert out is not theta  # a new array: callers may write into it
    np.testing.assert_array_equal(out, KannalaBrandt().distort(theta))
    np.testing.assert_array_equal(lens.undistort(theta, theta_max=1.0), theta)
    np.testing.assert_array_equal(lens.distort_derivative(theta), np.ones_like(theta))
    assert lens.is_monotonic(np.pi)
