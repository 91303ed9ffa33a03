"""The Kannala-Brandt lens: distortion polynomial, its derivative and its inverse."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.camera import KannalaBrandt, distort_theta, distort_theta_derivative, undistort_theta

KB = (-0.0185, 0.0041, -0.0029, 0.0003)


def test_undistort_theta_inverts_and_flags_out_of_range():
    k = np.asarray(KB)
    theta = np.linspace(0, np.radians(96), 200)
    np.testing.assert_allclose(undistort_theta(distort_theta(theta, k), k, theta_max=1.68), theta,
                               atol=1e-10)
    beyond = undistort_theta(np.array([5.0]), k, theta_max=1.68)
    assert beyond[0] > 1.68


def test_derivative_matches_finite_differences():
    theta = np.linspace(0.01, 1.6, 50)
    h = 1e-6
    numeric = (distort_theta(theta + h, KB) - distort_theta(theta - h, KB)) / (2 * h)
    np.testing.assert_allclose(distort_theta_derivative(theta, KB), numeric, rtol=1e-7)


def test_model_object_is_the_functions():
    lens = KannalaBrandt(KB)
    theta = np.linspace(0, 1.6, 100)
    np.testing.assert_array_equal(lens.distort(theta), distort_theta(theta, np.asarray(KB)))
    np.testing.assert_array_equal(lens.undistort(lens.distort(theta), theta_max=1.68),
                                  undistort_theta(distort_theta(theta, KB), KB, theta_max=1.68))
    assert lens.is_monotonic(1.68)
    assert not KannalaBrandt((-0.5, 0.0, 0.0, 0.0)).is_monotonic(1.68)


@pytest.mark.parametrize("theta", [0.0, 0.3, 1.2])
def test_matches_cv2_fisheye_distort(theta):
    """θ_d · f is the distance from the principal point cv2.fisheye.distortPoints gives."""
    import cv2

    x = np.tan(theta)  # normalised pinhole coordinate of a ray at θ (θ < 90°)
    d = cv2.fisheye.distortPoints(np.array([[[x, 0.0]]]), np.eye(3), np.asarray(KB).reshape(4, 1))
    assert float(d[0, 0, 0]) == pytest.approx(float(distort_theta(np.array(theta), KB)), abs=1e-9)
