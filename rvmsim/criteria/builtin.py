"""The paper's eleven EC functions (section V), as a plugin of the EC registry.

Written against the public API of :mod:`rvmsim.criteria` only (and its public modules
:mod:`~rvmsim.criteria.solves` and :mod:`~rvmsim.criteria.feasibility`, which hold these ECs'
closed-form sub-solves and feasibility reasons), exactly as a customer's plugin is
(docs/criteria.md); nothing else in the package knows these ECs.

========  =====================================================================  ======
EC        measurement (on the RVM label image, H × W px)                          unit
========  =====================================================================  ======
1-1       the F and G lower 150 × 150 mm stripe patches are wholly visible: present,  0/1
          not touching the image border, not next to void or vehicle-body pixels
1-2       area of the F and G vertical stripes (incl. patches) / image area         ‰
1-3       d = rows above the highest pixel of objects A, B, C, / H                   %
1-4       area of the horizontal stripe on B / image area                           ‰
2-1       t_c: bumper height at the horizontal centre / H                           %
2-2       (t_l + t_r)/2: bumper heights at the left and right edges / H             %
2-3       |t_l − t_r|                                                               px
2-4       no garnish or trunk pixel in the upper part of the image                  0/1
3-1       |x of the centre of cross guideline 2 − x of the image centre|           px
3-2       y of the centre of cross guideline 3 / H                                  %
4-1       width / height of the pattern board's bounding box                        –
========  =====================================================================  ======

The px ECs (2-3 along y, 3-1 along x: :attr:`EcDefinition.pixel_axis`) are pixels of the RVM
image of record whatever size they are measured at (:mod:`rvmsim.criteria.record`).

Conventions: pixel centres at integer (column, row); distances from the top of the image are
measured to pixel edges (a pixel in row r starts r px below the top).  Bumper heights are
counts of bumper pixels per column, averaged over ``edge_columns`` columns (at each edge,
and centred on the middle), which gives the sub-pixel figures the paper reports.  The centre
of a guideline is the midpoint of its leftmost and rightmost pixels; its height there is the
mean row of its pixels in the three columns around that midpoint.

Default ranges and sigmoids: the paper's thresholds, with sigmoid coefficients chosen so
that the paper's reported measurements give the paper's reported scores (section VII-B);
each is noted with the pair it reproduces.
"""

from __future__ import annotations

import dataclasses
import math

import cv2
import numpy as np

from .. import labels as L
# The package's public API, exactly as a customer's plugin imports it.
from . import (FAIL, INK, PASS, Canvas, EcDefinition, EcValue, LabelGroup, LabelsAbsent,
               LabelSource, Measurement, MeasureOptions, Sigmoid, SubSolve, Window, bounding_box,
               count_label, label_mask, offset, range_zero)
from .builtin_groups import ABC, BLOCKERS, BOARD
from .builtin_groups import FG as _FG
from .builtin_groups import GUIDE2, GUIDE3, UPPER_BODY, F, G, bumper_spans
from .builtin_stack import STACK_MEASURES
from .feasibility import fg_patches_reason
from .solves import (board_aspect_scale, board_aspect_scale_stack, guide_centre_shift,
                     guide_centre_shift_stack, guide_height_shift, guide_height_shift_stack)

__all__ = ["ECS", "bumper_spans", "F", "G", "ABC", "GUIDE2", "GUIDE3", "BOARD", "UPPER_BODY"]

#: What may not touch a visible patch: vehicle body, void, user-supplied parts.
_LUT_BLOCKERS = L.lut(BLOCKERS)


# ---------------------------------------------------------------------------- EC 1: FMVSS 111
def _patch_visible(sub: np.ndarray, win: Window, label: int, shape: tuple[int, int]) -> bool:
    """Present (≥ 4 px), not touching the image border, no void/body pixel next to it."""

    if sub.size == 0:
        return False
    mask = label_mask(sub, label)
    if cv2.countNonZero(mask) < 4:
        return False
    h, w = shape
    bx, by, bw, bh = cv2.boundingRect(mask)
    x, y = bx + win[0], by + win[1]
    if x == 0 or y == 0 or x + bw == w or y + bh == h:
        return False  # cut by the image border
    crop = sub[max(by - 1, 0) : by + bh + 1, max(bx - 1, 0) : bx + bw + 1]
    grown = cv2.dilate((crop == label).astype(np.uint8), np.ones((3, 3), np.uint8),
                       borderType=cv2.BORDER_CONSTANT, borderValue=0)
    blockers = cv2.LUT(crop, _LUT_BLOCKERS)
    return not np.any(blockers[grown > 0])


def _measure_1_1(src: LabelSource, options: MeasureOptions) -> Measurement:
    visible = {}
    for c, group in _FG.items():
        win = src.window(group)
        visible[c] = _patch_visible(src.pixels(win), win, L.object_patch(c), src.shape)
    return Measurement(1.0 if all(visible.values()) else 0.0, visible)


def _draw_1_1(canvas: Canvas, item: EcValue, visible: dict[str, bool]) -> None:

    for c in "FG":
        patch = (canvas.labels == L.object_patch(c)).astype(np.uint8)
        canvas.fill(patch > 0, (0, 255, 255))
        contours, _ = cv2.findContours(patch, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        cv2.drawContours(canvas.image, contours, -1, PASS if visible.get(c) else FAIL,
                         canvas.line_width)


def _measure_1_2(src: LabelSource, options: MeasureOptions) -> Measurement:
    h, w = src.shape
    fg = 0
    for c, group in _FG.items():
        sub = src.pixels(src.window(group))
        fg += count_label(sub, L.object_stripe(c)) + count_label(sub, L.object_patch(c))
    return Measurement(1000.0 * fg / (h * w))


def _draw_1_2(canvas: Canvas, item: EcValue, detail: object) -> None:
    for c in "FG":
        canvas.fill(canvas.labels == L.object_stripe(c), (255, 0, 255))


def _measure_1_3(src: LabelSource, options: MeasureOptions) -> Measurement:
    """Highest point of A, B, C (all three must be in the image)."""

    win = src.window(ABC)
    sub = src.pixels(win)
    top_row = None
    if sub.size and all(count_label(sub, L.object_body(c)) + count_label(sub, L.object_stripe(c))
                        > 0 for c in "ABC"):
        box = bounding_box(cv2.LUT(sub, ABC.lut))
        top_row = None if box is None else box[1] + win[1]
    return Measurement(None if top_row is None else 100.0 * top_row / src.shape[0], top_row)


def _draw_1_3(canvas: Canvas, item: EcValue, top_row: int | None) -> None:

    if top_row is None:
        return
    x = int(np.nonzero(np.isin(canvas.labels[top_row], ABC.labels))[0].mean())
    colour = canvas.status(item)
    cv2.arrowedLine(canvas.image, (x, 0), (x, top_row), colour, canvas.line_width,
                    tipLength=0.15)
    canvas.text(f"top margin d {canvas.value_text(item)}", (x, top_row / 2.0), colour)


def _measure_1_4(src: LabelSource, options: MeasureOptions) -> Measurement:
    h, w = src.shape
    return Measurement(1000.0 * count_label(src.pixels(src.window(ABC)), L.object_stripe("B"))
                       / (h * w))


def _draw_1_4(canvas: Canvas, item: EcValue, detail: object) -> None:
    canvas.fill(canvas.labels == L.object_stripe("B"), (255, 120, 0))


# ---------------------------------------------------------------------------- EC 2: body
BumperColumns = dict[str, tuple[float, float, float]]


def _bumper_columns(src: LabelSource, options: MeasureOptions) -> BumperColumns:
    """Per bumper height t_l, t_r, t_c: (centre column, top row, height), px; shared."""
    def compute() -> BumperColumns:
        h, w = src.shape
        out = {}
        for name, (a, b) in bumper_spans(w, options.edge_columns).items():
            t = float(np.count_nonzero(src.columns(a, b) == L.BUMPER)) / max(b - a, 1)
            out[name] = ((a + b - 1) / 2.0, float(h) - t, t)
        return out

    return src.shared(("bumper_columns", options.edge_columns), compute)


def _bumper_regions(shape: tuple[int, int], options: MeasureOptions) -> list[Window]:
    h, w = shape
    return [(a, 0, b, h) for a, b in bumper_spans(w, options.edge_columns).values()]


def _measure_2_1(src: LabelSource, options: MeasureOptions) -> Measurement:
    cols = _bumper_columns(src, options)
    return Measurement(100.0 * cols["t_c"][2] / src.shape[0], cols)


def _measure_2_2(src: LabelSource, options: MeasureOptions) -> Measurement:
    cols = _bumper_columns(src, options)
    return Measurement(100.0 * (cols["t_l"][2] + cols["t_r"][2]) / 2.0 / src.shape[0], cols)


def _measure_2_3(src: LabelSource, options: MeasureOptions) -> Measurement:
    cols = _bumper_columns(src, options)
    return Measurement(abs(cols["t_l"][2] - cols["t_r"][2]), cols)


#: The bumper heights' names as the labels spell them out.
_BUMPER_NAMES = {"t_l": "bumper height, left edge", "t_r": "bumper height, right edge",
                 "t_c": "bumper height, centre"}


def _draw_bumper(canvas: Canvas, item: EcValue, cols: BumperColumns, names: tuple[str, ...]
                 ) -> None:
    """Each bumper height as a thick line up from the bottom, labelled at its top."""

    h, w = canvas.shape
    for name in names:
        xc, top, t = cols[name]
        x = int(round(xc))
        cv2.line(canvas.image, (x, h - 1), (x, int(round(top))), canvas.status(item),
                 canvas.line_width * 2)
        canvas.text(f"{_BUMPER_NAMES[name]} {t:.1f} px", (xc, top), canvas.status(item))


def _draw_2_1(canvas: Canvas, item: EcValue, cols: BumperColumns) -> None:
    _draw_bumper(canvas, item, cols, ("t_c",))


def _draw_2_2(canvas: Canvas, item: EcValue, cols: BumperColumns) -> None:
    _draw_bumper(canvas, item, cols, ("t_l", "t_r"))


def _draw_2_3(canvas: Canvas, item: EcValue, cols: BumperColumns) -> None:
    """The difference of the edge bumper heights, labelled between their tops."""
    (xl, top_l, _), (xr, top_r, _) = cols["t_l"], cols["t_r"]
    canvas.text(f"bumper heights, left − right {canvas.value_text(item)}",
                ((xl + xr) / 2.0, max(top_l, top_r)), canvas.status(item))


def _measure_2_4(src: LabelSource, options: MeasureOptions) -> Measurement:
    """No garnish/trunk in the upper region."""

    rows = options.upper_rows(src.shape[0])
    x0, y0, x1, y1 = src.window(UPPER_BODY)
    y1 = min(y1, rows)
    body_up = 0
    if x1 > x0 and y1 > y0:
        body_up = cv2.countNonZero(cv2.LUT(src.pixels((x0, y0, x1, y1)), UPPER_BODY.lut))
    return Measurement(1.0 if body_up == 0 else 0.0, rows)


def _draw_2_4(canvas: Canvas, item: EcValue, rows: int) -> None:

    cv2.line(canvas.image, (0, rows), (canvas.shape[1] - 1, rows), canvas.status(item),
             canvas.line_width)
    canvas.text("upper region free of body ✓" if item.value == 1 else "body in upper region ✗",
                (canvas.shape[1] / 4.0, rows), canvas.status(item))


# ---------------------------------------------------------------------------- EC 3: guidelines
def _guide_center(src: LabelSource, group: LabelGroup) -> tuple[float, float] | None:
    win = src.window(group)
    sub = src.pixels(win)
    label = group.labels[0]
    box = bounding_box(label_mask(sub, label)) if sub.size else None
    if box is None:
        return None
    x, y, bw, bh = box
    xc = x + (bw - 1) / 2.0
    c0 = max(int(math.floor(xc)) - 1, x)
    c1 = min(int(math.ceil(xc)) + 2, x + bw)
    rows = np.nonzero(sub[y : y + bh, c0:c1] == label)[0]
    yc = y + float(rows.mean()) if rows.size else y + (bh - 1) / 2.0
    return (xc + win[0], yc + win[1])


def _measure_3_1(src: LabelSource, options: MeasureOptions) -> Measurement:
    g2 = _guide_center(src, GUIDE2)
    return Measurement(None if g2 is None else abs(g2[0] - (src.shape[1] - 1) / 2.0), g2)


def _measure_3_2(src: LabelSource, options: MeasureOptions) -> Measurement:
    g3 = _guide_center(src, GUIDE3)
    return Measurement(None if g3 is None else 100.0 * (g3[1] + 0.5) / src.shape[0], g3)


def _draw_guide(canvas: Canvas, item: EcValue, centre: tuple[float, float] | None,
                marker: int, label: str) -> None:

    if centre is None:
        return
    gx, gy = centre
    s = canvas.text_scale
    cv2.drawMarker(canvas.image, (int(round(gx)), int(round(gy))), canvas.status(item), marker,
                   int(20 * s) + 6, canvas.line_width)
    canvas.text(f"{label} {canvas.value_text(item)}", (gx, gy), canvas.status(item))


def _draw_3_1(canvas: Canvas, item: EcValue, centre: tuple[float, float] | None) -> None:
    """Guideline 2's centre and the image's dashed centre line."""

    h, w = canvas.shape
    cx = int((w - 1) / 2.0)
    for yy in range(0, h, max(6, h // 60)):
        cv2.line(canvas.image, (cx, yy), (cx, min(h - 1, yy + max(3, h // 120))), INK, 1)
    _draw_guide(canvas, item, centre, cv2.MARKER_CROSS, "guideline 2 off centre")


def _draw_3_2(canvas: Canvas, item: EcValue, centre: tuple[float, float] | None) -> None:
    """Guideline 3's centre and the dashed 45 % and 55 % rows."""

    h, w = canvas.shape
    for frac in (0.45, 0.55):
        yy = int(round(frac * h))
        for xx in range(0, w, max(6, w // 80)):
            cv2.line(canvas.image, (xx, yy), (min(w - 1, xx + max(3, w // 160)), yy),
                     (200, 200, 0), 1)
    _draw_guide(canvas, item, centre, cv2.MARKER_TILTED_CROSS, "guideline 3 height")


# ---------------------------------------------------------------------------- EC 4: board
def _measure_4_1(src: LabelSource, options: MeasureOptions) -> Measurement:
    win = src.window(BOARD)
    sub = src.pixels(win)
    box = bounding_box(label_mask(sub, L.BOARD)) if sub.size else None
    board = None if box is None else offset(box, win)
    return Measurement(None if board is None else board[2] / board[3], board)


def _draw_4_1(canvas: Canvas, item: EcValue, board: tuple[int, int, int, int] | None) -> None:

    if board is None:
        return
    bx, by, bw, bh = board
    cv2.rectangle(canvas.image, (bx, by), (bx + bw - 1, by + bh - 1), canvas.status(item),
                  canvas.line_width)
    canvas.text(f"board width/height {canvas.value_text(item, '{:.3f}')}", (bx, by),
                canvas.status(item))


# ---------------------------------------------------------------------------- hooks
def _absent(labels: tuple[int, ...], what: str, short: str) -> LabelsAbsent:
    """The feasibility reason of an EC that measures ``labels``: none is in the fisheye
    image (``what``: the labels, with their verb)."""
    return LabelsAbsent(labels, f"{what} not in the fisheye image at all", f"no {short} in view")


_FG_ABSENT = _absent((L.object_stripe("F"), L.object_patch("F"), L.object_stripe("G"),
                      L.object_patch("G")), "the F and G stripes are", "F, G stripes")
_BUMPER_ABSENT = _absent((L.BUMPER,), "the bumper is", "bumper")
#: The sub-solves run in this order (4-1 does not depend on the shifts; 3-2 reads the
#: horizontal shift 3-1 sets, and 3-1 the vertical shift 3-2 sets).
_SOLVE_4_1 = SubSolve("adv_h_scale", (L.BOARD,), board_aspect_scale, order=0,
                      solve_stack=board_aspect_scale_stack)
_SOLVE_3_2 = SubSolve("adv_v_shift", (L.guide_cross(3),), guide_height_shift, order=1,
                      solve_stack=guide_height_shift_stack)
_SOLVE_3_1 = SubSolve("adv_h_shift", (L.guide_cross(2),), guide_centre_shift, range_zero,
                      order=2, solve_stack=guide_centre_shift_stack)

# ---------------------------------------------------------------------------- the eleven
_INF = math.inf
ECS = [
    EcDefinition("1-1", "fg_lower_patches_visible", "", (F, G), _measure_1_1, _draw_1_1,
                 (1, 1), None, binary=True,
                 description="lower 150 × 150 mm of the F and G stripes wholly visible",
                 infeasibility=fg_patches_reason,
                 needs=((L.object_patch("F"),), (L.object_patch("G"),))),
    EcDefinition("1-2", "fg_stripe_area_ratio", "‰", (F, G), _measure_1_2, _draw_1_2,
                 (10, None), Sigmoid(0.5, 10, 0, _INF),  # larger is better; 26.12 ‰ -> 1.00
                 description="area of the F and G vertical stripes / image area",
                 infeasibility=_FG_ABSENT),
    EcDefinition("1-3", "abc_top_margin_ratio", "%", (ABC,), _measure_1_3, _draw_1_3,
                 (15, None), Sigmoid(0.43, 15, 0, _INF),  # >= 15 %; 25.70 % -> 0.99
                 description="distance d from the image top to the highest point of A, B, C "
                             "/ height", needs=(ABC.labels,)),
    EcDefinition("1-4", "b_stripe_area_ratio", "‰", (ABC,), _measure_1_4, _draw_1_4,
                 (0.1, None), Sigmoid(23.1, 0.1, 0, _INF),  # larger is better; 0.2 ‰ -> 0.91
                 description="area of the horizontal stripe on B / image area",
                 infeasibility=_absent((L.object_stripe("B"),), "object B's stripe is",
                                       "B stripe")),
    EcDefinition("2-1", "bumper_center_ratio", "%", (), _measure_2_1, _draw_2_1,
                 (4, 8), Sigmoid(3.0, 4, 3.0, 8),  # 4–8 %; 3.45 % -> 0.16
                 description="bumper height t_c at the horizontal centre / image height",
                 regions=_bumper_regions, infeasibility=_BUMPER_ABSENT),
    EcDefinition("2-2", "bumper_side_ratio", "%", (), _measure_2_2, _draw_2_2,
                 (8, 16), Sigmoid(2.69, 8, 2.69, 16),  # 8–16 %; 17.75 % -> 0.009
                 description="mean of the bumper heights t_l, t_r at the image edges / image "
                             "height",
                 regions=_bumper_regions, infeasibility=_BUMPER_ABSENT),
    EcDefinition("2-3", "bumper_side_difference", "px", (), _measure_2_3, _draw_2_3,
                 (None, 5), Sigmoid(0, -_INF, 1.17, 5),  # smaller is better; 1.08 px -> 0.99
                 description="|t_l − t_r|", regions=_bumper_regions, pixel_axis="y",
                 needs=((L.BUMPER,),)),
    EcDefinition("2-4", "no_body_in_upper_region", "", (UPPER_BODY,), _measure_2_4, _draw_2_4,
                 (1, 1), None, binary=True,
                 description="no garnish or trunk in the upper part of the image"),
    EcDefinition("3-1", "guide2_center_offset", "px", (GUIDE2,), _measure_3_1, _draw_3_1,
                 (None, 5), Sigmoid(0, -_INF, 0.937, 5),  # smaller is better; 0.09 px -> 0.99
                 description="|x of the centre of guideline 2 − x of the image centre|",
                 sub_solve=_SOLVE_3_1, pixel_axis="x",
                 infeasibility=_absent((L.guide_cross(2),), "cross guideline 2 is",
                                       "guideline 2")),
    EcDefinition("3-2", "guide3_height_ratio", "%", (GUIDE3,), _measure_3_2, _draw_3_2,
                 (45, 55), Sigmoid(1.0, 45, 1.0, 55),  # 45–55 %; 55 % -> 0.5
                 description="y of the centre of guideline 3 / image height",
                 sub_solve=_SOLVE_3_2,
                 infeasibility=_absent((L.guide_cross(3),), "cross guideline 3 is",
                                       "guideline 3")),
    EcDefinition("4-1", "board_aspect_ratio", "", (BOARD,), _measure_4_1, _draw_4_1,
                 (0.9, 1.1), Sigmoid(42.4, 0.9, 42.4, 1.1),  # 0.9–1.1; 1.08 -> 0.7
                 description="width / height of the calibration pattern board",
                 sub_solve=_SOLVE_4_1,
                 infeasibility=_absent((L.BOARD,), "the pattern board is", "board")),
]
# each with its stack measure (K images at once; rvmsim.criteria.builtin_stack)
ECS = [dataclasses.replace(ec, measure_stack=STACK_MEASURES[ec.id]) for ec in ECS]
