"""The paper's ECs on K label images at once: the stack measure functions
(:attr:`EcDefinition.measure_stack <rvmsim.criteria.EcDefinition>`) of
:mod:`rvmsim.criteria.builtin`'s ECs, image for image the measurement of its measure
function (tests/criteria/test_builtin_stack.py compares them on rendered and synthetic
images).  Written against the public API of :mod:`rvmsim.criteria`, as
:mod:`~rvmsim.criteria.builtin` is.

Each reads a group's window once for all images (:class:`rvmsim.criteria.LabelStack`),
finds masks, pixel counts and bounding boxes of every image with one array operation each
(:func:`~rvmsim.criteria.stack_mask`, :func:`~rvmsim.criteria.stack_counts`,
:func:`~rvmsim.criteria.stack_boxes`), and loops over the images only for a few numbers.
"""

from __future__ import annotations

import math

import numpy as np

from .. import labels as L
from . import (LabelGroup, LabelStack, Measurement, MeasureOptions, Window, stack_boxes,
               stack_counts, stack_mask)
from .builtin_groups import ABC, BLOCKERS, BOARD, FG, GUIDE2, GUIDE3, UPPER_BODY, bumper_spans

__all__ = ["STACK_MEASURES"]

Box = tuple[int, int, int, int]


def _grown(mask: np.ndarray) -> np.ndarray:
    """The 3 × 3 dilation of each image of a 0/1 mask ((h, w, K) uint8), zero outside."""
    rows = mask.copy()
    rows[1:] |= mask[:-1]
    rows[:-1] |= mask[1:]
    out = rows.copy()
    out[:, 1:] |= rows[:, :-1]
    out[:, :-1] |= rows[:, 1:]
    return out


def _patches_visible(stack: LabelStack, win: Window, label: int) -> list[bool]:
    """Per image: the patch ``label`` is present (≥ 4 px), not touching the image border,
    with no void/body pixel next to it (:func:`rvmsim.criteria.builtin._patch_visible`)."""
    sub = stack.pixels(win)
    if sub.size == 0:
        return [False] * stack.n
    mask = stack_mask(sub, (label,))
    enough = stack_counts(mask) >= 4
    h, w = stack.shape
    ok, boxes = [], stack_boxes(mask)
    for k, box in enumerate(boxes):
        if not enough[k] or box is None:
            ok.append(False)
            continue
        x, y = box[0] + win[0], box[1] + win[1]
        ok.append(not (x == 0 or y == 0 or x + box[2] == w or y + box[3] == h))
    if any(ok):  # a blocker next to a patch pixel: under the patch's dilation, which lies
        # in the box of the patches grown by 1 px (the window's part a crop reads)
        held = [b for b, v in zip(boxes, ok) if v and b is not None]
        x0 = max(min(b[0] for b in held) - 1, 0)
        y0 = max(min(b[1] for b in held) - 1, 0)
        x1 = max(b[0] + b[2] for b in held) + 1
        y1 = max(b[1] + b[3] for b in held) + 1
        near = (slice(y0, y1), slice(x0, x1))
        touched = stack_counts(_grown(mask[near]) & stack_mask(sub[near], BLOCKERS)) > 0
        ok = [v and not bool(t) for v, t in zip(ok, touched)]
    return ok


def _stack_1_1(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    seen = {c: _patches_visible(stack, stack.window(g), L.object_patch(c))
            for c, g in FG.items()}
    return [Measurement(1.0 if all(seen[c][k] for c in FG) else 0.0,
                        {c: seen[c][k] for c in FG}) for k in range(stack.n)]


def _stack_1_2(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    h, w = stack.shape
    fg = np.zeros(stack.n, np.int64)
    for c, g in FG.items():
        fg += stack_counts(stack_mask(stack.pixels(stack.window(g)),
                                      (L.object_stripe(c), L.object_patch(c))))
    return [Measurement(1000.0 * int(n) / (h * w)) for n in fg]


def _stack_1_3(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    win = stack.window(ABC)
    sub = stack.pixels(win)
    if sub.size == 0:
        return [Measurement(None, None)] * stack.n
    present = np.ones(stack.n, bool)
    for c in "ABC":
        present &= stack_counts(stack_mask(sub, (L.object_body(c), L.object_stripe(c)))) > 0
    out = []
    for k, box in enumerate(stack_boxes(stack_mask(sub, ABC.labels))):
        top = box[1] + win[1] if present[k] and box is not None else None
        out.append(Measurement(None if top is None else 100.0 * top / stack.shape[0], top))
    return out


def _stack_1_4(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    h, w = stack.shape
    n = stack_counts(stack_mask(stack.pixels(stack.window(ABC)), (L.object_stripe("B"),)))
    return [Measurement(1000.0 * int(c) / (h * w)) for c in n]


BumperColumns = dict[str, tuple[float, float, float]]


def _bumper_columns(stack: LabelStack, options: MeasureOptions) -> list[BumperColumns]:
    """Per image, per bumper height t_l, t_r, t_c: (centre column, top row, height) px."""
    def compute() -> list[BumperColumns]:
        h, w = stack.shape
        out: list[BumperColumns] = [{} for _ in range(stack.n)]
        for name, (a, b) in bumper_spans(w, options.edge_columns).items():
            counts = stack_counts(stack_mask(stack.columns(a, b), (L.BUMPER,)))
            for k, n in enumerate(counts):
                t = float(int(n)) / max(b - a, 1)
                out[k][name] = ((a + b - 1) / 2.0, float(h) - t, t)
        return out

    return stack.shared(("bumper_columns", options.edge_columns), compute)


def _stack_2_1(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    return [Measurement(100.0 * c["t_c"][2] / stack.shape[0], c)
            for c in _bumper_columns(stack, options)]


def _stack_2_2(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    return [Measurement(100.0 * (c["t_l"][2] + c["t_r"][2]) / 2.0 / stack.shape[0], c)
            for c in _bumper_columns(stack, options)]


def _stack_2_3(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    return [Measurement(abs(c["t_l"][2] - c["t_r"][2]), c)
            for c in _bumper_columns(stack, options)]


def _stack_2_4(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    rows = options.upper_rows(stack.shape[0])
    x0, y0, x1, y1 = stack.window(UPPER_BODY)
    y1 = min(y1, rows)
    if not (x1 > x0 and y1 > y0):
        return [Measurement(1.0, rows)] * stack.n
    up = stack_counts(stack_mask(stack.pixels((x0, y0, x1, y1)), UPPER_BODY.labels))
    return [Measurement(1.0 if n == 0 else 0.0, rows) for n in up]


def _guide_centres(stack: LabelStack, group: LabelGroup) -> list[tuple[float, float] | None]:
    """Per image, a guideline's centre (:func:`rvmsim.criteria.builtin._guide_center`)."""
    win = stack.window(group)
    sub = stack.pixels(win)
    if sub.size == 0:
        return [None] * stack.n
    label = group.labels[0]
    out: list[tuple[float, float] | None] = []
    for k, box in enumerate(stack_boxes(stack_mask(sub, (label,)))):
        if box is None:
            out.append(None)
            continue
        x, y, bw, bh = box
        xc = x + (bw - 1) / 2.0
        c0 = max(int(math.floor(xc)) - 1, x)
        c1 = min(int(math.ceil(xc)) + 2, x + bw)
        rows = np.nonzero(sub[y : y + bh, c0:c1, k] == label)[0]
        yc = y + float(rows.mean()) if rows.size else y + (bh - 1) / 2.0
        out.append((xc + win[0], yc + win[1]))
    return out


def _stack_3_1(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    mid = (stack.shape[1] - 1) / 2.0
    return [Measurement(None if g is None else abs(g[0] - mid), g)
            for g in _guide_centres(stack, GUIDE2)]


def _stack_3_2(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    h = stack.shape[0]
    return [Measurement(None if g is None else 100.0 * (g[1] + 0.5) / h, g)
            for g in _guide_centres(stack, GUIDE3)]


def _stack_4_1(stack: LabelStack, options: MeasureOptions) -> list[Measurement]:
    win = stack.window(BOARD)
    sub = stack.pixels(win)
    if sub.size == 0:
        return [Measurement(None, None)] * stack.n
    out = []
    for box in stack_boxes(stack_mask(sub, (L.BOARD,))):
        board: Box | None = None if box is None else (box[0] + win[0], box[1] + win[1],
                                                      box[2], box[3])
        out.append(Measurement(None if board is None else board[2] / board[3], board))
    return out


#: EC id → its stack measure function.
STACK_MEASURES = {"1-1": _stack_1_1, "1-2": _stack_1_2, "1-3": _stack_1_3,
                  "1-4": _stack_1_4, "2-1": _stack_2_1, "2-2": _stack_2_2,
                  "2-3": _stack_2_3, "2-4": _stack_2_4, "3-1": _stack_3_1,
                  "3-2": _stack_3_2, "4-1": _stack_4_1}
