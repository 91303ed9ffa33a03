"""The single-track reversing model against an independent integration of its equations and
against the closed forms: circles about the instantaneous centre, straight lines at zero."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rvmsim.guidelines import RunningGear, reverse_paths, trajectory_lines
from rvmsim.scene import GuidelineSpec

GEAR = RunningGear(wheelbase_m=2.8, rear_overhang_m=1.0, track_m=1.6, max_road_wheel_deg=38.0,
                   steering_ratio=15.0)


def _integrate(gear: RunningGear, corner_x: float, steering_deg: float, travel: np.ndarray
               ) -> np.ndarray:
    """The bicycle model reversing at unit speed, integrated numerically: the rear axle's
    centre moves against the heading f(ψ) = (sin ψ, −cos ψ), the heading turns at
    −tan δ / wheelbase per metre; the corner is rigidly attached (lateral r(ψ) = (cos ψ,
    sin ψ), ``rear_overhang`` behind the axle)."""
    delta = math.radians(float(gear.road_wheel_deg(steering_deg)))

    def rhs(_s: float, y: np.ndarray) -> list[float]:
        psi = y[2]
        return [-math.sin(psi), math.cos(psi), -math.tan(delta) / gear.wheelbase_m]

    sol = solve_ivp(rhs, (0.0, float(travel[-1])), [0.0, -gear.rear_overhang_m, 0.0],
                    t_eval=travel, rtol=1e-11, atol=1e-12)
    ax, az, psi = sol.y
    f = np.stack([np.sin(psi), -np.cos(psi)], axis=1)
    r = np.stack([np.cos(psi), np.sin(psi)], axis=1)
    return np.stack([ax, az], axis=1) + corner_x * r - gear.rear_overhang_m * f


@pytest.mark.parametrize("steering_deg", [0.0, 120.0, -300.0, 500.0])
def test_the_closed_form_is_the_integrated_model(steering_deg: float) -> None:
    travel = np.linspace(0.0, 4.0, 41)
    corners = np.array([[-0.95, 0.0], [0.95, 0.0]])
    paths = reverse_paths(GEAR, corners, steering_deg, travel)
    for i, x in enumerate(corners[:, 0]):
        np.testing.assert_allclose(paths[i], _integrate(GEAR, x, steering_deg, travel),
                                   atol=1e-7)


@pytest.mark.parametrize("steering_deg", [90.0, -250.0])
def test_a_constant_angle_gives_circles_about_the_instantaneous_centre(steering_deg: float
                                                                       ) -> None:
    delta = math.radians(steering_deg / GEAR.steering_ratio)  # within the lock
    icr = np.array([GEAR.wheelbase_m / math.tan(delta), -GEAR.rear_overhang_m])
    corners = np.array([[-0.9, 0.0], [0.9, 0.0], [0.0, 0.0]])
    paths = reverse_paths(GEAR, corners, steering_deg, np.linspace(0.0, 3.0, 31))
    for i in range(len(corners)):
        radius = np.linalg.norm(paths[i] - icr, axis=1)
        np.testing.assert_allclose(radius, np.linalg.norm(corners[i] - icr), atol=1e-9)
    # reversing moves the rear away from the car (+Z), and it swings to the ICR's side
    assert np.all(np.diff(paths[2][:5, 1]) > 0)
    assert np.sign(paths[2][-1, 0]) == np.sign(icr[0])


def test_zero_steering_gives_straight_lines() -> None:
    spec = GuidelineSpec()
    lines = trajectory_lines(GEAR, 1.8, spec, 0.0)
    assert [l.name for l in lines] == ["trajectory_neg_x", "trajectory_pos_x"]
    for line, x in zip(lines, (-0.9, 0.9)):
        np.testing.assert_allclose(line.points_m[:, 0], x + spec.width_lines.margin
                                   * np.sign(x), atol=1e-12)
        assert line.points_m[0, 1] == 0.0
        assert line.points_m[-1, 1] == pytest.approx(spec.trajectory.travel)


def test_the_lock_is_the_inner_wheel_of_an_ackermann_linkage() -> None:
    lock = math.radians(GEAR.lock_deg)
    radius = GEAR.wheelbase_m / math.tan(lock)  # ICR to the rear axle's centre
    inner = math.degrees(math.atan(GEAR.wheelbase_m / (radius - GEAR.track_m / 2)))
    assert inner == pytest.approx(GEAR.max_road_wheel_deg, abs=1e-9)
    assert GEAR.steering_range_deg == pytest.approx(GEAR.lock_deg * GEAR.steering_ratio)
    # beyond the range the wheels stay at the lock
    assert float(GEAR.road_wheel_deg(5000.0)) == pytest.approx(GEAR.lock_deg)
    assert float(GEAR.road_wheel_deg(-5000.0)) == pytest.approx(-GEAR.lock_deg)


def test_a_steering_table_is_read_linearly_and_mirrored() -> None:
    gear = RunningGear(2.8, 1.0, 1.6, 38.0, steering_table=((0.0, 0.0), (100.0, 8.0),
                                                            (400.0, 40.0)))
    assert float(gear.road_wheel_deg(50.0)) == pytest.approx(4.0)
    assert float(gear.road_wheel_deg(-250.0)) == pytest.approx(-24.0)
    # the range ends where the table reaches the lock
    assert float(gear.road_wheel_deg(gear.steering_range_deg)) == pytest.approx(gear.lock_deg)
