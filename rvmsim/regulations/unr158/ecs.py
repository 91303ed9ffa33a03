"""UN Regulation No. 158's rear-view camera system (RVCS) field of vision, as ECs.

A plugin of the EC registry (the bundled criteria set ``unr158``, market ``unr158``),
measured on a scene at the ``unr158`` site (:mod:`rvmsim.scene.sitedefs`: three rows of
cylinders 0.3 m to 3.5 m behind the vehicle, as wide as it).  The regulation's field-of-
vision requirement, as docs/markets.md reads it (⚠ there marks every choice):

- row 1: a 0.15 m × 0.15 m area or the top of each cylinder visible at one position at least;
- rows 2 and 3: the whole cylinder visible;
- the image size of the far row on the display: the horizontal widths of its three
  cylinders must *average* at least 5′ and *each* be at least 3′ (R158 §16.1.1 as quoted in
  UNECE document VRU-Proxi-17-05; FMVSS 111 S5.5.1(b) has the same form).

=======  ================================================================================  ==
EC       measurement                                                                        unit
=======  ================================================================================  ==
R158-1   min over row 1 of max(largest shown square of the side / 0.15 m, shown fraction     ×
         of the top face): ≥ 1 when a 0.15 m square or the whole top shows
R158-2   min over row 2 of the shown fraction of the whole silhouette (hidden parts count)   %
R158-3   the same for row 3                                                                  %
R158-4   min(mean / ``mean_arcmin``, least / ``each_arcmin``) of row 3's visual angles on   ×
         the display (5′ and 3′)
=======  ================================================================================  ==

Each measurable-only-from-the-scene EC has a feasibility reason read from the fisheye labels
(a part no ISP setting can show: hidden behind the body, cut by the image circle or the
sensor border).
"""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np

from ...criteria import (Canvas, EcDefinition, EcValue, IspView, LabelSource, Measurement, MeasureOptions,
                         SceneContext, Sigmoid)
from ...criteria.sigmoid import Criterion
from ..fmvss111.ecs import _draw_widths, object_widths, size_margin
from ..objects import silhouette, silhouette_fractions
from ..siteobjects import hidden_reason, row_objects, shown_area

__all__ = ["ECS", "AREA_M", "ROW_AREA", "ROW_WHOLE", "FAR_ROW", "EACH_ARCMIN", "MEAN_ARCMIN",
           "area_ec", "whole_ec", "size_ec"]

#: Row 1: the side of the square area that must show, metres.
AREA_M = 0.15
#: The rows of the ``unr158`` site each EC reads.
ROW_AREA, ROW_WHOLE, FAR_ROW = "row1", ("row2", "row3"), "row3"
#: The far row's visual angles on the display, arc-minutes: each at least
#: :data:`EACH_ARCMIN`, their average at least :data:`MEAN_ARCMIN` (R158 §16.1.1, quoted in
#: UNECE VRU-Proxi-17-05; EC parameters ``each_arcmin`` and ``mean_arcmin``).
EACH_ARCMIN = 3.0
MEAN_ARCMIN = 5.0

#: Per object its figure and fisheye outline, and the candidate's ISP view (for drawing).
_AreaDetail = tuple[dict[str, float], dict[str, np.ndarray], IspView]


# ---------------------------------------------------------------------------- area or top
def _area_measure(ec_id: str, row: str, area_m: float, top: bool
                  ) -> Callable[[LabelSource, MeasureOptions], Measurement]:
    def measure(src: LabelSource, options: MeasureOptions) -> Measurement:
        ctx = src.context
        if ctx is None or src.isp is None:
            return Measurement(None)
        size = options.parameter(ec_id, "area_m", area_m)
        margins: dict[str, float] = {}
        for obj in row_objects(ctx, row):
            shown = shown_area(src, obj.name)
            if shown is not None:
                margins[obj.name] = shown.margin(size, top)
        if not margins:
            return Measurement(None)
        outlines = {n: sil.outline for n in margins
                    if (sil := silhouette(ctx, n)) is not None}  # per scene, for drawing
        return Measurement(min(margins.values()), (margins, outlines, src.isp))
    return measure


def _area_feasibility(ec_id: str, row: str, area_m: float, top: bool
                      ) -> Callable[[SceneContext, Criterion, MeasureOptions],
                                    tuple[str, str] | None]:
    def reason(ctx: SceneContext, criterion: Criterion, options: MeasureOptions
               ) -> tuple[str, str] | None:
        size = options.parameter(ec_id, "area_m", area_m)
        src = LabelSource(np.zeros((1, 1), np.uint8), context=ctx)
        for obj in row_objects(ctx, row):
            shown = shown_area(src, obj.name, bound=True)
            if shown is not None and not criterion.passes(shown.margin(size, top)):
                needs = f"{100 * size:.0f} cm" + (" or the whole top" if top else "")
                tops = f" and {100 * shown.top_fraction:.0f} % of its top" if top else ""
                return (f"object {obj.name} shows at most a {100 * shown.square_m:.0f} cm "
                        f"square of its side{tops} in the whole fisheye image (needs "
                        f"{needs})", f"{obj.name} hidden")
        return None
    return reason


def _draw_margins(canvas: Canvas, item: EcValue, detail: _AreaDetail | None,
                  text: Callable[[str, float], str]) -> None:
    """Each object's outline and its figure next to it: objects that meet the EC's limit in
    a light blue, the others in the EC's status colour."""

    if detail is None:
        return
    values, outlines, isp = detail
    for name, value in values.items():
        outline = outlines.get(name)
        if outline is None or len(outline) < 3:
            continue
        uv, ok = isp.to_output(outline)
        if not np.all(ok):
            continue
        ok_here = item.low is None or value >= item.low
        colour = (0, 200, 255) if ok_here else canvas.status(item)
        pts = np.round(uv * 16).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(canvas.image, [pts], True, colour, canvas.line_width, cv2.LINE_AA,
                      shift=4)
        x, y = uv.min(axis=0)
        canvas.text(text(name, value), (x, y), colour)


def area_ec(ec_id: str, row: str, area_m: float, name: str, description: str,
            top: bool = True) -> EcDefinition:
    """An EC: min over ``row``'s objects of max(shown square / ``area_m``, shown top
    fraction) (``top``; the square alone without, see
    :func:`rvmsim.regulations.siteobjects.shown_area`)."""
    return EcDefinition(
        id=ec_id, name=name, unit="x", groups=(),
        measure=_area_measure(ec_id, row, area_m, top),
        annotate=lambda c, i, d: _draw_margins(c, i, d, lambda n, v: f"{n} ×{v:.2f}"),
        default_range=(1.0, None), default_sigmoid=Sigmoid.from_range(1.0, None, tolerance=0.3),
        description=description, parameters={"area_m": area_m}, uses_scene=True,
        infeasibility=_area_feasibility(ec_id, row, area_m, top))


# ---------------------------------------------------------------------------- whole cylinder
def _whole_measure(rows: tuple[str, ...]) -> Callable[[LabelSource, MeasureOptions],
                                                     Measurement]:
    def measure(src: LabelSource, options: MeasureOptions) -> Measurement:
        ctx = src.context
        if ctx is None or src.isp is None:
            return Measurement(None)
        names = [o.name for r in rows for o in row_objects(ctx, r)]
        fractions, outlines = silhouette_fractions(src, names)
        if not fractions:
            return Measurement(None)
        return Measurement(min(fractions.values()), (fractions, outlines, src.isp))
    return measure


def _whole_feasibility(rows: tuple[str, ...]
                       ) -> Callable[[SceneContext, Criterion, MeasureOptions],
                                     tuple[str, str] | None]:
    def reason(ctx: SceneContext, criterion: Criterion, options: MeasureOptions
               ) -> tuple[str, str] | None:
        for r in rows:
            for obj in row_objects(ctx, r):
                sil = silhouette(ctx, obj.name)
                bound = 0.0 if sil is None or sil.area == 0 else 100.0 * sil.visible_area / sil.area
                if not criterion.passes(bound):
                    why = hidden_reason(ctx, obj.name) or "cannot show"
                    return f"object {obj.name} {why} in the fisheye image", f"{obj.name} hidden"
        return None
    return reason


def whole_ec(ec_id: str, rows: tuple[str, ...], name: str, description: str,
             least_percent: float = 100.0) -> EcDefinition:
    """An EC: min over ``rows``' objects of the shown % of the whole silhouette (hidden
    parts count), passing at ``least_percent`` and above."""
    return EcDefinition(
        id=ec_id, name=name, unit="%", groups=(), measure=_whole_measure(rows),
        annotate=lambda c, i, d: _draw_margins(c, i, d, lambda n, v: f"{n} {v:.0f} % shown"),
        default_range=(least_percent, None),
        default_sigmoid=Sigmoid.from_range(least_percent, None,
                                           tolerance=5.0 if least_percent >= 50 else 0.5),
        description=description, uses_scene=True,
        infeasibility=_whole_feasibility(rows))


# ---------------------------------------------------------------------------- image size
def _size_measure(ec_id: str, row: str, each: float, mean: float | None
                  ) -> Callable[[LabelSource, MeasureOptions], Measurement]:
    def measure(src: LabelSource, options: MeasureOptions) -> Measurement:
        ctx = src.context
        if ctx is None or src.isp is None:
            return Measurement(None)
        names = [o.name for o in row_objects(ctx, row)]
        widths = object_widths(src, options, names) if names else None
        if not widths:
            return Measurement(None)
        angles = [w["arcmin"] for w in widths.values()]
        mean_limit = None if mean is None else options.parameter(ec_id, "mean_arcmin", mean)
        return Measurement(size_margin(angles, options.parameter(ec_id, "each_arcmin", each),
                                       mean_limit), widths)
    return measure


def size_ec(ec_id: str, row: str, each_arcmin: float, name: str, description: str, *,
            mean_arcmin: float | None = None) -> EcDefinition:
    """An EC: the margin of ``row``'s objects' visual angles on the display (from the
    driver's eye point, :func:`rvmsim.regulations.fmvss111.ecs.object_widths`) against
    "each ≥ ``each_arcmin``" and, if given, "their average ≥ ``mean_arcmin``"
    (:func:`rvmsim.regulations.fmvss111.ecs.size_margin`; ≥ 1 passes)."""
    parameters = {"each_arcmin": each_arcmin}
    if mean_arcmin is not None:
        parameters["mean_arcmin"] = mean_arcmin
    return EcDefinition(
        id=ec_id, name=name, unit="x", groups=(),
        measure=_size_measure(ec_id, row, each_arcmin, mean_arcmin),
        annotate=lambda c, i, d: _draw_widths(c, i, d, ("px", "mm", "arcmin")),
        default_range=(1.0, None), default_sigmoid=Sigmoid.from_range(1.0, None, tolerance=0.3),
        description=description, parameters=parameters, uses_scene=True)


ECS = [
    area_ec("R158-1", ROW_AREA, AREA_M, "r158_row1_area_or_top",
            "row 1: min over cylinders of max(shown square/0.15 m, shown top fraction)"),
    whole_ec("R158-2", ("row2",), "r158_row2_whole", "row 2: least shown % of a whole cylinder"),
    whole_ec("R158-3", ("row3",), "r158_row3_whole", "row 3: least shown % of a whole cylinder"),
    size_ec("R158-4", FAR_ROW, EACH_ARCMIN, "r158_row3_display_size",
            "row 3: min(mean/5', least/3') of the cylinders' visual angles on the display",
            mean_arcmin=MEAN_ARCMIN),
]
