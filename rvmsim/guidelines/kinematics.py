"""The car reversing at a constant steering angle: a kinematic single-track (Ackermann) model.

The model
---------
The two front wheels are one steered wheel on the centreline, the rear wheels one fixed wheel
on the rear axle's centre; no wheel slips.  At a constant steering angle every point of the car
then turns about one point, the instantaneous centre of rotation (ICR), on the rear axle's
line, at ``R = wheelbase / tan δ`` from the axle's centre (δ: the single-track road-wheel
angle); a point at distance ``ρ`` from the ICR moves on a circle of radius ``ρ``.  At δ = 0
every point moves straight back.

The single-track angle δ comes from the steering wheel through ``steering_ratio`` (δ = wheel
angle / ratio) or ``steering_table`` (linear between its rows, mirrored for the other side).
The lock: ``max_road_wheel_deg`` is the inner front wheel's angle at full lock; the inner
wheel of an Ackermann linkage turns about the same ICR, ``track / 2`` nearer to it, so the
single-track lock is ``atan(wheelbase / (wheelbase / tan δ_inner + track / 2))``.  The
steering range (±100 %) is the steering-wheel angle at that lock.

Limits: walking pace on flat ground (no tyre slip angles, no body roll, no load transfer);
rear wheels not steered; the angle held constant over the whole travel; the wheelbase,
overhang and track of the design (tyre wear and load do not change them).  A real car at
parking speed follows the model to within a few centimetres over the 3 m a guideline shows
(tyre slip grows with speed and lateral acceleration, both near zero there).

Convention
----------
Scene frame (:mod:`rvmsim.camera`): X toward the driver's side, Z rearward, on the ground
(x, z) in metres; the rear-most point's plane is z = 0 and the rear axle lies at
z = −rear_overhang.  A positive steering-wheel angle turns the front wheels toward +X: the ICR
lies on the +X side, and reversing, the rear swings toward +X.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError
from ..scene import Scene

__all__ = ["RunningGear", "running_gear", "has_running_gear", "reverse_paths"]


@dataclass(frozen=True)
class RunningGear:
    """The car's running gear (the scene's ``vehicle`` keys), metres and degrees."""

    wheelbase_m: float
    rear_overhang_m: float
    track_m: float
    max_road_wheel_deg: float
    steering_ratio: float | None = None
    steering_table: tuple[tuple[float, float], ...] | None = None

    @property
    def lock_deg(self) -> float:
        """The single-track road-wheel angle at full lock, degrees (see the module docstring)."""
        inner = math.radians(self.max_road_wheel_deg)
        radius = self.wheelbase_m / math.tan(inner) + self.track_m / 2.0
        return math.degrees(math.atan(self.wheelbase_m / radius))

    @property
    def steering_range_deg(self) -> float:
        """The steering-wheel angle at full lock (100 % of the range), degrees."""
        if self.steering_table is not None:
            wheel, road = np.array(self.steering_table).T
            return float(np.interp(self.lock_deg, road, wheel)) if road[-1] >= self.lock_deg \
                else float(wheel[-1])
        assert self.steering_ratio is not None
        return self.lock_deg * self.steering_ratio

    def road_wheel_deg(self, steering_wheel_deg: np.ndarray | float) -> np.ndarray:
        """Single-track road-wheel angle δ (degrees, signed) of steering-wheel angles (degrees),
        held at the lock beyond it."""
        a = np.asarray(steering_wheel_deg, np.float64)
        if self.steering_table is not None:
            wheel, road = np.array(self.steering_table).T
            delta = np.sign(a) * np.interp(np.abs(a), wheel, road)
        else:
            assert self.steering_ratio is not None
            delta = a / self.steering_ratio
        return np.clip(delta, -self.lock_deg, self.lock_deg)

    def icr_x_m(self, steering_wheel_deg: float) -> float:
        """Signed lateral place of the ICR (m, on the rear axle's line z = −rear_overhang);
        ``inf`` at zero steering."""
        delta = math.radians(float(self.road_wheel_deg(steering_wheel_deg)))
        return math.inf if delta == 0.0 else self.wheelbase_m / math.tan(delta)


def has_running_gear(scene: Scene) -> bool:
    """Whether the scene's vehicle has every key the guidelines need
    (:func:`running_gear` reads them, and names the first one missing)."""
    return scene.vehicle is not None and scene.vehicle.running_gear_problem() is None


def running_gear(scene: Scene) -> RunningGear:
    """The scene's running gear.

    Raises
    ------
    SceneError
        A scene without a vehicle, or without one of the keys the guidelines need (naming the
        scene file and the key).
    """
    v = scene.vehicle
    if v is None:
        raise SceneError(scene.source, "vehicle", "missing: the guidelines need the car")
    bad = v.running_gear_problem()
    if bad is not None:
        raise SceneError(scene.source, *bad)
    assert (v.wheelbase is not None and v.rear_overhang is not None and v.track is not None
            and v.max_road_wheel_deg is not None)
    table = None if v.steering_table is None else tuple(tuple(r) for r in v.steering_table)
    return RunningGear(v.wheelbase, v.rear_overhang, v.track, v.max_road_wheel_deg,
                       v.steering_ratio, table)  # type: ignore[arg-type]


def reverse_paths(gear: RunningGear, points_xz: np.ndarray, steering_wheel_deg: float,
                  travel_m: np.ndarray) -> np.ndarray:
    """Where points of the car are after it reverses ``travel_m`` at a constant steering angle.

    Parameters
    ----------
    gear : RunningGear
    points_xz : (P, 2) float
        Points of the car at the start, (x, z) m on the ground, scene frame.
    steering_wheel_deg : float
        Steering-wheel angle, degrees (positive: toward +X; see the module docstring).
    travel_m : (T,) float
        Arc lengths travelled by the rear axle's centre, m (≥ 0).

    Returns
    -------
    (P, T, 2) float64
        The points' places, (x, z) m.

    Convention
    ----------
    Closed form: a rotation by −s / R about the ICR (x = R, z = −rear_overhang), which moves
    the axle's centre toward +Z; at R = ∞ a translation by s along +Z.
    """
    pts = np.asarray(points_xz, np.float64).reshape(-1, 2)
    s = np.asarray(travel_m, np.float64).reshape(-1)
    radius = gear.icr_x_m(steering_wheel_deg)
    if math.isinf(radius):
        return pts[:, None, :] + np.stack([np.zeros_like(s), s], axis=1)[None, :, :]
    centre = np.array([radius, -gear.rear_overhang_m])
    phi = -s / radius
    c, sn = np.cos(phi), np.sin(phi)
    rel = pts - centre  # (P, 2)
    x = centre[0] + c[None, :] * rel[:, :1] - sn[None, :] * rel[:, 1:]
    z = centre[1] + sn[None, :] * rel[:, :1] + c[None, :] * rel[:, 1:]
    return np.stack([x, z], axis=2)
