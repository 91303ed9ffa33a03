"""ECs beyond the paper: FMVSS No. 111 on the display, full visibility of A–E, resolution.

A plugin of the EC registry written against the public API only (the worked example of an EC
that needs more than the RVM label pixels: the scene's geometry, ``source.context``, and the
candidate's ISP map, ``source.isp``; see docs/criteria.md).  The bundled criteria set
``fmvss111-full`` selects the paper's eleven and these three.

========  ===========================================================================  ====
EC        measurement                                                                  unit
========  ===========================================================================  ====
1-5       S5.5.1(b): the smallest fraction, over A–E, of an object's silhouette            %
          (hidden parts included) that the RVM image shows
1-6       S5.5.2: image size margin min(mean/5′, min/3′) of the visual angles of the        ×
          horizontal widths of A, B, C on the display, from the driver's eye point
6-1       resolution margin at A–C: min(limit / magnification, px per degree / limit)       ×
========  ===========================================================================  ====

Formulas and defaults: docs/criteria.md.  The limits are EC parameters (a criteria file
changes them under ``criteria: {id: {parameters: …}}``); the S5.5.2 figures and the display's
defaults are named in :mod:`rvmsim.scene.fmvss111` (⚠ values there are unverified).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import cv2
import numpy as np

from ...criteria import (Canvas, EcDefinition, EcValue, IspView, LabelSource, Measurement, MeasureOptions,
                         SceneContext, Sigmoid)
from ...scene import fmvss111 as rule

if TYPE_CHECKING:
    from ...scene import Display

from ..objects import silhouette_fractions, width_edges

__all__ = ["ECS", "FULL_VIEW_OBJECTS", "SIZE_OBJECTS", "MAX_MAGNIFICATION",
           "MIN_PIXELS_PER_DEGREE", "object_widths", "ObjectWidths", "size_margin"]

#: Per object letter: its figures (px, mm, arcmin, magnification, px_per_deg, x, y and the
#: width's ends x0, y0, x1, y1), as :func:`object_widths` gives them.
ObjectWidths = dict[str, dict[str, float]]
#: EC 1-5's detail: per object its visible fraction (%) and fisheye outline, and the ISP view.
_SilhouetteDetail = tuple[dict[str, float], dict[str, np.ndarray], IspView]

#: S5.5.1(b): objects whose full width and height must be visible.
FULL_VIEW_OBJECTS = "ABCDE"
#: S5.5.2: objects whose image size is judged (also where 6-1 measures resolution).
SIZE_OBJECTS = "ABC"
#: EC 6-1: an RVM px that shows less than 1/2 fisheye px (in its most magnified direction)
#: adds no detail, only blur.
MAX_MAGNIFICATION = 2.0
#: EC 6-1: RVM px per degree of the camera's view at A–C, at least (not from the rule: our
#: choice): the 0.3 m objects at ~6.5 m (≈ 2.6°) then span ≥ 5 RVM px each.
MIN_PIXELS_PER_DEGREE = 2.0
#: Arc-minutes per radian.
_ARCMIN = 180.0 * 60.0 / math.pi


# ---------------------------------------------------------------------------- 1-5
def _measure_1_5(src: LabelSource, options: MeasureOptions) -> Measurement:
    """min over A–E of visible / whole silhouette (fisheye px of its 1-px-eroded interior;
    visible: the label image shows the object there and the RVM image samples it)."""
    ctx, isp = src.context, src.isp
    if ctx is None or isp is None:
        return Measurement(None)
    fractions, outlines = silhouette_fractions(src, FULL_VIEW_OBJECTS)
    if not fractions:
        return Measurement(None)
    return Measurement(min(fractions.values()), (fractions, outlines, isp))


def _draw_1_5(canvas: Canvas, item: EcValue, detail: _SilhouetteDetail | None) -> None:

    if detail is None or item.value is None:
        return
    fractions, outlines, isp = detail
    for letter, frac in fractions.items():
        colour = canvas.status(item) if frac < 100.0 else (0, 200, 255)
        if len(outlines[letter]) >= 3:
            uv, ok = isp.to_output(outlines[letter])
            if np.all(ok):
                pts = np.round(uv * 16).astype(np.int32).reshape(-1, 1, 2)
                cv2.polylines(canvas.image, [pts], True, colour, canvas.line_width,
                              cv2.LINE_AA, shift=4)
                if frac < 100.0:  # (whole ones: the outline's colour says so)
                    x, y = uv.min(axis=0)
                    canvas.text(f"{letter} {frac:.0f} % visible", (x, y), colour)


# ---------------------------------------------------------------------------- 1-6 and 6-1
def object_widths(src: LabelSource, options: MeasureOptions,
                  names: Sequence[str] = SIZE_OBJECTS) -> ObjectWidths | None:
    """Per object of ``names`` (default :data:`SIZE_OBJECTS`; FMVSS letters or a site's
    object names): its horizontal width in RVM px (``px``), on the
    display (``mm``), the visual angle from the eye point (``arcmin``), the RVM px per degree
    of the camera's view (``px_per_deg``), the ISP's magnification there (``magnification``,
    RVM px per px of the camera's sensor, whatever fraction of it was rendered) and its RVM
    position (``x``, ``y``).  None without a scene or map.

    Convention: width = the distance between the RVM images of the two points where the
    camera's lines of sight touch the cylinder at half its height; on the display the RVM
    image is scaled to fit the active area; θ = 2·atan(w·cos(viewing angle) / 2d).
    """
    ctx, isp = src.context, src.isp
    if ctx is None or isp is None:
        return None
    return src.shared(("fmvss111.widths", options.display, tuple(names)),
                      lambda: _widths(ctx.display(options.display), ctx, isp, names))


def _widths(display: Display, ctx: SceneContext, isp: IspView,
            names: Sequence[str]) -> ObjectWidths | None:
    edges = {c: width_edges(ctx, c) for c in names}
    if any(e is None for e in edges.values()):
        return None
    pts = np.concatenate([np.concatenate([e.points, e.centre]) for e in edges.values() if e])
    uv, ok = isp.to_output(pts)
    if not np.all(ok):
        return None
    mag = isp.magnification(pts[2::3]) * ctx.sensor_scale  # per px of the real sensor
    mx, my = display.mm_per_rvm_px((isp.output.width, isp.output.height))
    cos_view = math.cos(math.radians(display.viewing_angle_deg))
    out = {}
    for k, (letter, e) in enumerate(edges.items()):
        assert e is not None
        (xl, yl), (xr, yr), (x, y) = uv[3 * k : 3 * k + 3]
        px = math.hypot(xr - xl, yr - yl)
        mm = math.hypot((xr - xl) * mx, (yr - yl) * my)
        arcmin = _ARCMIN * 2.0 * math.atan(mm * cos_view / (2.0 * display.eye_distance_mm))
        out[letter] = {"px": px, "mm": mm, "arcmin": arcmin, "magnification": float(mag[k]),
                       "px_per_deg": px / e.angle_deg if e.angle_deg > 0 else 0.0,
                       "x": float(x), "y": float(y), "x0": float(xl), "y0": float(yl),
                       "x1": float(xr), "y1": float(yr)}
    return out


def size_margin(angles_arcmin: list[float], each_arcmin: float,
                mean_arcmin: float | None = None) -> float | None:
    """The margin of visual angles against a rule of the form "each at least ``each``, and
    their average at least ``mean``" (FMVSS 111 S5.5.1(b), UN R158 §16.1.1; ``mean`` None:
    each alone): min(mean / ``mean_arcmin``, least / ``each_arcmin``), ≥ 1 passes.

    Parameters
    ----------
    angles_arcmin : list of float
        The objects' visual angles on the display, arc-minutes (at least one).
    each_arcmin, mean_arcmin : float
        The limits, arc-minutes; a limit ≤ 0 is no limit.

    Returns
    -------
    float or None
        None when no limit applies.
    """
    margins = []
    if each_arcmin > 0:
        margins.append(min(angles_arcmin) / each_arcmin)
    if mean_arcmin is not None and mean_arcmin > 0:
        margins.append(sum(angles_arcmin) / len(angles_arcmin) / mean_arcmin)
    return min(margins) if margins else None


def _measure_1_6(src: LabelSource, options: MeasureOptions) -> Measurement:
    """min(mean / mean limit, min / each limit) of the objects' visual angles (≥ 1 passes)."""
    widths = object_widths(src, options)
    if widths is None:
        return Measurement(None)
    mean_limit = options.parameter("1-6", "mean_arcmin", rule.IMAGE_SIZE_MEAN_ARCMIN)
    each_limit = options.parameter("1-6", "each_arcmin", rule.IMAGE_SIZE_MIN_ARCMIN)
    angles = [w["arcmin"] for w in widths.values()]
    return Measurement(size_margin(angles, each_limit, mean_limit), widths)


def _draw_widths(canvas: Canvas, item: EcValue, widths: ObjectWidths | None,
                 keys: tuple[str, ...]) -> None:
    """Each object's figures as a label at the object (1-6: at the middle of its width,
    drawn as a line across it; 6-1: at its axis)."""

    if not widths:
        return
    colour = canvas.status(item)
    sizes = keys[0] == "px"
    for letter, w in widths.items():
        text = f"{letter} {_FORMATS[keys].format(**{k: w[k] for k in keys})}"
        if sizes:
            ends = [(int(round(w["x0"])), int(round(w["y0"]))),
                    (int(round(w["x1"])), int(round(w["y1"])))]
            cv2.line(canvas.image, ends[0], ends[1], colour, canvas.line_width)
            at = ((w["x0"] + w["x1"]) / 2.0, (w["y0"] + w["y1"]) / 2.0)
        else:
            at = (w["x"], w["y"])
        canvas.text(text, at, colour)


_FORMATS = {("px", "mm", "arcmin"): "{arcmin:.1f}′ wide on the display ({px:.1f} px)",
            ("magnification", "px_per_deg"): "magnification ×{magnification:.2f}, "
                                             "{px_per_deg:.1f} px/°"}


def _draw_1_6(canvas: Canvas, item: EcValue, widths: ObjectWidths | None) -> None:
    _draw_widths(canvas, item, widths, ("px", "mm", "arcmin"))


def _measure_6_1(src: LabelSource, options: MeasureOptions) -> Measurement:
    """min over A–C of min(max magnification / magnification, px per degree / minimum)."""
    widths = object_widths(src, options)
    if widths is None:
        return Measurement(None)
    max_mag = options.parameter("6-1", "max_magnification", MAX_MAGNIFICATION)
    min_ppd = options.parameter("6-1", "min_pixels_per_degree", MIN_PIXELS_PER_DEGREE)
    margins = []
    for w in widths.values():
        zoom = max_mag / w["magnification"] if w["magnification"] > 0 else math.inf
        ppd = w["px_per_deg"] / min_ppd if min_ppd > 0 else math.inf
        margins.append(min(zoom, ppd))
    value = min(margins)
    return Measurement(None if math.isinf(value) else float(value), widths)


def _draw_6_1(canvas: Canvas, item: EcValue, widths: ObjectWidths | None) -> None:
    _draw_widths(canvas, item, widths, ("magnification", "px_per_deg"))


ECS = [
    EcDefinition(
        id="1-5", name="abcde_full_silhouette", unit="%", groups=(),
        measure=_measure_1_5, annotate=_draw_1_5, default_range=(100.0, None),
        default_sigmoid=Sigmoid.from_range(100.0, None, tolerance=5.0),
        description="smallest visible fraction of an A–E silhouette (hidden parts included)",
        uses_scene=True),
    EcDefinition(
        id="1-6", name="abc_display_size_margin", unit="x", groups=(),
        measure=_measure_1_6, annotate=_draw_1_6, default_range=(1.0, None),
        default_sigmoid=Sigmoid.from_range(1.0, None, tolerance=0.3),
        description="min(mean/5', min/3') of A, B, C's visual angles on the display",
        parameters={"mean_arcmin": rule.IMAGE_SIZE_MEAN_ARCMIN,
                    "each_arcmin": rule.IMAGE_SIZE_MIN_ARCMIN}, uses_scene=True),
    EcDefinition(
        id="6-1", name="abc_resolution_margin", unit="x", groups=(),
        measure=_measure_6_1, annotate=_draw_6_1, default_range=(1.0, None),
        default_sigmoid=Sigmoid.from_range(1.0, None, tolerance=0.3),
        description="min(limit/magnification, px per degree/limit) at A, B, C",
        parameters={"max_magnification": MAX_MAGNIFICATION,
                    "min_pixels_per_degree": MIN_PIXELS_PER_DEGREE}, uses_scene=True),
]
