"""Reading K label images at once: one candidate's RVM label images on K fisheye images
(robust tuning's nominal image and variation samples), measured together.

An EC may give, besides its measure function, a *stack* measure function
(:attr:`EcDefinition.measure_stack <rvmsim.criteria.EcDefinition>`): the same measurement
on every image of a :class:`LabelStack` in one call, vectorised over the images, so that K
images cost little more than one.  It must give, image for image, exactly the
:class:`~rvmsim.criteria.Measurement` its measure function gives on that image alone;
:func:`measure_stack_ecs` falls back to the measure function, image by image, for an EC
without one.  The helpers here (:func:`stack_mask`, :func:`stack_counts`,
:func:`stack_boxes`) do the usual work of a measurement on all images at once.

Conventions: as :mod:`rvmsim.criteria.measure`; a stack's pixels are (rows, columns,
images) uint8, image ``k`` in channel ``k``; a window holds its group's pixels on *every*
image (any window that does gives the same measurements).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .groups import EMPTY_WINDOW, LabelGroup, Window, group_window, group_windows
from .measure import (EcFailedError, LabelSource, MeasureOptions, Measurements, MeasuredEc,
                      PixelReads, error_text, image_name, measure_ecs, measurement_of,
                      passes_through)

__all__ = ["LabelStack", "StackMeasureFn", "measure_stack_ecs", "stack_mask", "stack_counts",
           "stack_boxes"]

#: ``measure_stack(stack, options)`` → one :class:`Measurement` (or value) per image.
StackMeasureFn = Callable[["LabelStack", MeasureOptions], Sequence[Any]]


class LabelStack(PixelReads):
    """The label pixels of K RVM label images of one size, read together: here whole
    images.  :meth:`pixels` and :meth:`columns` give (…, K) arrays, image ``k`` last.

    Parameters
    ----------
    labels : (H, W, K) uint8
        Image ``k`` in channel ``k`` (ids from :mod:`rvmsim.labels`).
    groups : sequence of LabelGroup
        The groups measurements ask windows of: each one's window is the box of its windows
        on every image (:func:`rvmsim.criteria.group_windows`).
    sources : sequence of LabelSource, optional
        Image ``k`` on its own, for ECs without a stack measure (default: made from
        ``labels``).
    """

    def __init__(self, labels: np.ndarray, groups: Sequence[LabelGroup], *,
                 sources: Sequence[LabelSource] | None = None):
        labels = np.asarray(labels)
        if labels.ndim != 3 or labels.dtype != np.uint8:
            raise TypeError(f"labels must be an (H, W, K) uint8 stack, got {labels.dtype} "
                            f"{labels.shape}")
        self.labels = labels
        self.shape: tuple[int, int] = (int(labels.shape[0]), int(labels.shape[1]))
        self.n = int(labels.shape[2])
        planes = [np.ascontiguousarray(labels[:, :, k]) for k in range(self.n)]
        found = [group_windows(p, groups) for p in planes]
        self._windows = {g.name: union_box([f[g.name] for f in found]) for g in groups}
        self.sources = (list(sources) if sources is not None
                        else [LabelSource(p, groups) for p in planes])
        self._shared = {}

    def window(self, group: LabelGroup | str) -> Window:
        """A window that holds every pixel of ``group``, and the pixels next to them, on
        every image."""
        return group_window(self._windows, group)


def union_box(windows: Sequence[Window]) -> Window:
    """The box of the non-empty ``windows`` (:data:`EMPTY_WINDOW` if none is)."""
    boxes = [w for w in windows if w[2] > w[0] and w[3] > w[1]]
    if not boxes:
        return EMPTY_WINDOW
    return (min(b[0] for b in boxes), min(b[1] for b in boxes), max(b[2] for b in boxes),
            max(b[3] for b in boxes))


def measure_stack_ecs(stack: LabelStack, ecs: Sequence[MeasuredEc],
                      options: MeasureOptions) -> list[Measurements]:
    """Each image's measurements (:func:`rvmsim.criteria.measure.measure_ecs`): an EC with a
    stack measure measures every image in one call, any other one image by image on
    ``stack.sources``.

    Raises
    ------
    CriteriaError
        As :func:`~rvmsim.criteria.measure.measure_ecs`; also a stack measure that gives
        another number of measurements than images.
    """
    plain = [ec for ec in ecs if getattr(ec, "measure_stack", None) is None]
    each = ([measure_ecs(src, plain, options) for src in stack.sources] if plain
            else [Measurements({}, (stack.shape[1], stack.shape[0])) for _ in range(stack.n)])
    for ec in ecs:
        fn = getattr(ec, "measure_stack", None)
        if fn is None:
            continue
        try:
            got = list(fn(stack, options))
            if len(got) != stack.n:
                raise ValueError(f"measure_stack gave {len(got)} measurements for "
                                 f"{stack.n} images")
            found = [measurement_of(ec, m) for m in got]
        except BaseException as err:  # noqa: BLE001 - the EC's own code: see passes_through
            if passes_through(err, ec.plugin):
                raise
            raise EcFailedError(ec.plugin or "<ec>", ec.id, "measure_stack",
                                image_name(stack.sources[0]), error_text(err)) from None
        for m, (value, detail) in zip(each, found):
            m.values[ec.id] = value
            m.details[ec.id] = detail
    order = [ec.id for ec in ecs]  # the ECs' order, as measure_ecs gives it
    return [Measurements({k: m.values[k] for k in order}, m.image_size,
                         {k: m.details[k] for k in order}) for m in each]


# ---------------------------------------------------------------------------- helpers
@functools.lru_cache(maxsize=256)
def _runs(ids: tuple[int, ...]) -> tuple[tuple[int, int], ...]:
    """Label ids as runs of consecutive ids: ((first, count), …)."""
    out: list[list[int]] = []
    for i in sorted(set(ids)):
        if out and out[-1][0] + out[-1][1] == i:
            out[-1][1] += 1
        else:
            out.append([i, 1])
    return tuple((a, n) for a, n in out)


def stack_mask(sub: np.ndarray, ids: Sequence[int]) -> np.ndarray:
    """1 where a pixel of ``sub`` ((h, w, K) uint8) is one of the labels ``ids``, else 0:
    (h, w, K) uint8.  A comparison per run of consecutive ids (a table lookup costs
    several times more per pixel)."""
    hit: np.ndarray | None = None
    for first, count in _runs(tuple(int(i) for i in ids)):
        # ids first … first + count − 1: (label − first) mod 256 < count
        run = (sub == first) if count == 1 else (
            np.subtract(sub, np.uint8(first), dtype=np.uint8) < count)
        hit = run if hit is None else np.logical_or(hit, run, out=hit)
    if hit is None:
        return np.zeros(sub.shape, np.uint8)
    return hit.view(np.uint8)


#: Rows summed in uint8 before widening (each sum of 0/1 stays ≤ 255).
_CHUNK = 255


def stack_counts(mask: np.ndarray) -> np.ndarray:
    """The non-zero pixels of each image of a 0/1 mask ((h, w, K) uint8): (K,) int64."""
    flat = mask.reshape(-1, mask.shape[-1])
    full = len(flat) // _CHUNK * _CHUNK
    # summing over the leading axis runs along contiguous rows of K: fast, unlike a sum
    # widened to int64 element by element
    part = np.add.reduce(flat[:full].reshape(_CHUNK, -1, flat.shape[1]), axis=0,
                         dtype=np.uint8)
    return part.sum(axis=0, dtype=np.int64) + flat[full:].sum(axis=0, dtype=np.int64)


def _any_along_columns(mask: np.ndarray) -> np.ndarray:
    """(h, w, K) uint8 → (h, K): the maximum over each row, by halving the columns (each
    step one elementwise maximum of contiguous blocks)."""
    m = mask
    while m.shape[1] > 1:
        half = m.shape[1] // 2
        folded = np.maximum(m[:, :half], m[:, half : 2 * half])
        if m.shape[1] % 2:
            folded[:, :1] = np.maximum(folded[:, :1], m[:, 2 * half :])
        m = folded
    return m[:, 0]


def stack_boxes(mask: np.ndarray) -> list[tuple[int, int, int, int] | None]:
    """Per image, ``(x, y, w, h)`` px of the non-zero pixels of a 0/1 mask ((h, w, K)
    uint8), as :func:`rvmsim.criteria.bounding_box` gives it; ``None`` where there are
    none."""
    h, w, k = mask.shape
    if h == 0 or w == 0:
        return [None] * k
    cols = mask.max(axis=0) > 0  # (w, K)
    rows = _any_along_columns(mask) > 0  # (h, K)
    has = cols.any(axis=0)
    x0, y0 = cols.argmax(axis=0), rows.argmax(axis=0)
    x1, y1 = w - cols[::-1].argmax(axis=0), h - rows[::-1].argmax(axis=0)
    return [(int(x0[i]), int(y0[i]), int(x1[i] - x0[i]), int(y1[i] - y0[i])) if has[i]
            else None for i in range(k)]
