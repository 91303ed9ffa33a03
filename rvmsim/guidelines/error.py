"""How far a car's guidelines land from where they claim: lines drawn through one view (the
table's: the pose a station measured, the car's ISP values) and looked at through another (the
car's true pose, the same ISP values).

Definitions
-----------
A line's point is a display point ``uv`` (px) drawn for a ground point ``G`` ((x, z) m).
Through the true view:

- **display error** (px): ``|true.to_display(G) − uv|``, how far from the line's place on
  the picture the ground point ``G`` really shows (counted where the true view shows ``G``);
- **ground error** (cm): ``100 · |display_to_ground(true, uv) − G|``, how far from ``G``
  the ground the driver sees under ``uv`` really lies (counted where the pixel's ray meets
  the ground).  Point by point: a slide along the line counts too.

A line's error is the largest over its counted points (NaN: no point counted).  The
table's rounding to 1/16 px (:mod:`.table`, at most 1/32 px) is not included.

With the ISP values the same in both views, the ground error does not depend on them (a
display pixel is one camera ray in both views): it is the ray of ``G`` from the measured
pose, ``R_meas⁻¹ (G − C_meas)``, cast from the true pose ``C_true + λ · R_true · r`` onto
the ground; the ISP values only decide which points are shown.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .overlay import GuidelineSet
from .project import DisplayLine, GuidelineView, display_to_ground

__all__ = ["PointErrors", "line_group", "point_errors", "line_errors"]


@dataclass(frozen=True, eq=False)
class PointErrors:
    """One line's points and their errors through the true view (the module docstring).

    Attributes
    ----------
    name, group : str
        The line's name and its group (:func:`line_group` by default).
    uv_px : (M, 2) float64
        The drawn display points, px (every shown piece, in order).
    ground_m : (M, 2) float64
        The ground points they were drawn for, (x, z) m.
    px : (M,) float64
        Display error, px (NaN where the true view does not show the ground point).
    cm : (M,) float64
        Ground error, cm (NaN where the pixel's ray misses the ground).
    """

    name: str
    group: str
    uv_px: np.ndarray
    ground_m: np.ndarray
    px: np.ndarray
    cm: np.ndarray

    @property
    def worst_px(self) -> float:
        """The largest display error, px (NaN: none counted)."""
        return float(np.nanmax(self.px)) if np.isfinite(self.px).any() else float("nan")

    @property
    def worst_cm(self) -> float:
        """The largest ground error, cm (NaN: none counted)."""
        return float(np.nanmax(self.cm)) if np.isfinite(self.cm).any() else float("nan")


def line_group(line: DisplayLine) -> str:
    """A line's group: a distance mark's name without its tick's side (``mark_1m``), the width
    lines (``width``), the trajectory lines of one steering angle (``trajectory_<a>deg``, the
    steering-wheel angle in degrees)."""
    if line.kind == "width":
        return "width"
    if line.kind == "trajectory":
        return f"trajectory_{line.steering_deg:g}deg"
    for side in ("_neg_x", "_pos_x"):
        if line.name.endswith(side):
            return line.name[:-len(side)]
    return line.name


def point_errors(gset: GuidelineSet, true_view: GuidelineView, *,
                 group: Callable[[DisplayLine], str] = line_group) -> list[PointErrors]:
    """Every line of ``gset`` (drawn through its own view) seen through ``true_view``.

    Parameters
    ----------
    gset : GuidelineSet
        The lines as drawn (the table's view: the measured pose).
    true_view : GuidelineView
        The camera at its true pose with the same ISP values and image of record.
    group : callable, optional
        A line's group name (default :func:`line_group`).

    Returns
    -------
    list of PointErrors
        One per line of :meth:`GuidelineSet.lines` that has a shown piece, in that order.

    Convention
    ----------
    See the module docstring; all points are projected in one batch.
    """
    lines = [line for line in gset.lines() if line.pieces]
    if not lines:
        return []
    uv = [np.concatenate([p.uv_px for p in line.pieces]) for line in lines]
    ground = [np.concatenate([p.ground_m for p in line.pieces]) for line in lines]
    all_uv, all_g = np.concatenate(uv), np.concatenate(ground)
    seen_uv, shown = true_view.to_display(all_g)
    px = np.where(shown, np.hypot(*(seen_uv - all_uv).T), np.nan)
    under, hits = display_to_ground(true_view, all_uv)
    cm = np.where(hits, 100.0 * np.hypot(*(under - all_g).T), np.nan)
    out, at = [], 0
    for line, u, g in zip(lines, uv, ground):
        n = len(u)
        out.append(PointErrors(line.name, group(line), u, g, px[at:at + n], cm[at:at + n]))
        at += n
    return out


def line_errors(gset: GuidelineSet, true_view: GuidelineView, *,
                group: Callable[[DisplayLine], str] = line_group
                ) -> dict[str, tuple[float, float]]:
    """Per group of lines, its largest display error (px) and ground error (cm) over its
    counted points (:func:`point_errors`; NaN: none counted), in the lines' order."""
    out: dict[str, tuple[float, float]] = {}
    for e in point_errors(gset, true_view, group=group):
        px, cm = out.get(e.group, (float("nan"), float("nan")))
        out[e.group] = (float(np.fmax(px, e.worst_px)), float(np.fmax(cm, e.worst_cm)))
    return out
