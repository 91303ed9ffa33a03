"""The guidelines on the ground: static distance marks and width lines, and the trajectory
lines of one steering angle, as polylines sampled every ``spec.step`` metres.

Convention
----------
Scene frame on the ground: (x, z) metres, X toward the driver's side, Z rearward from the
rear-most point (:mod:`rvmsim.guidelines.kinematics`).  Line names: ``mark_<d>m`` (or
``mark_<d>m_neg_x`` / ``_pos_x`` for ticks), ``width_neg_x`` / ``width_pos_x``,
``trajectory_neg_x`` / ``trajectory_pos_x``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..scene.guideline_spec import GuidelineSpec, LineKind
from .kinematics import RunningGear, reverse_paths

__all__ = ["GroundLine", "static_lines", "trajectory_lines", "half_width_m"]


@dataclass(frozen=True, eq=False)
class GroundLine:
    """One guideline on the ground.

    Attributes
    ----------
    name : str
    kind : str
        ``"mark"``, ``"width"`` or ``"trajectory"``.
    color : (float, float, float)
        RGB, 0–1.
    points_m : (N, 2) float64
        (x, z) m, in drawing order, about ``spec.step`` apart.
    steering_deg : float or None
        The steering-wheel angle of a trajectory line, degrees; None for a static line.
    """

    name: str
    kind: LineKind
    color: tuple[float, float, float]
    points_m: np.ndarray
    steering_deg: float | None = None


def _segment(a: tuple[float, float], b: tuple[float, float], step: float) -> np.ndarray:
    n = max(2, int(math.ceil(math.hypot(b[0] - a[0], b[1] - a[1]) / step)) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return (1 - t) * np.asarray(a, np.float64) + t * np.asarray(b, np.float64)


def half_width_m(width_m: float, spec: GuidelineSpec) -> float:
    """Lateral place (m, each side of the centreline) of the width and trajectory lines."""
    return width_m / 2.0 + spec.width_lines.margin


def static_lines(width_m: float, spec: GuidelineSpec) -> list[GroundLine]:
    """The distance marks (nearest first), then the width lines (−X side, +X side).

    Parameters
    ----------
    width_m : float
        The car's overall width, m.
    spec : GuidelineSpec
    """
    xw = half_width_m(width_m, spec)
    out: list[GroundLine] = []
    for mark in spec.marks:
        d, tag = mark.distance, f"{mark.distance:g}m"
        if mark.length is None or mark.length >= xw:
            out.append(GroundLine(f"mark_{tag}", "mark", mark.color,
                                  _segment((-xw, d), (xw, d), spec.step)))
        else:
            out.append(GroundLine(f"mark_{tag}_neg_x", "mark", mark.color,
                                  _segment((-xw, d), (-xw + mark.length, d), spec.step)))
            out.append(GroundLine(f"mark_{tag}_pos_x", "mark", mark.color,
                                  _segment((xw - mark.length, d), (xw, d), spec.step)))
    w = spec.width_lines
    if w.enabled:
        for side, x in (("neg_x", -xw), ("pos_x", xw)):
            out.append(GroundLine(f"width_{side}", "width", w.color,
                                  _segment((x, w.start), (x, w.end), spec.step)))
    return out


def trajectory_lines(gear: RunningGear, width_m: float, spec: GuidelineSpec,
                     steering_deg: float) -> list[GroundLine]:
    """The paths of the two rear corners (−X side, +X side) over ``spec.trajectory.travel`` m
    of reversing at ``steering_deg`` (steering-wheel degrees); none when disabled.

    Convention
    ----------
    The corners lie at x = ±(width / 2 + ``width_lines.margin``), z = 0; samples are about
    ``spec.step`` apart along the faster corner's path.
    """
    t = spec.trajectory
    if not t.enabled:
        return []
    xw = half_width_m(width_m, spec)
    corners = np.array([[-xw, 0.0], [xw, 0.0]])
    radius = gear.icr_x_m(steering_deg)
    reach = 1.0 if math.isinf(radius) else max(
        math.hypot(xw + abs(radius), gear.rear_overhang_m) / abs(radius), 1.0)
    n = max(2, int(math.ceil(t.travel * reach / spec.step)) + 1)
    paths = reverse_paths(gear, corners, steering_deg, np.linspace(0.0, t.travel, n))
    return [GroundLine(f"trajectory_{side}", "trajectory", t.color, paths[i], float(steering_deg))
            for i, side in enumerate(("neg_x", "pos_x"))]
