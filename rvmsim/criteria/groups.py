"""Label groups: the named sets of label ids an EC reads, and the windows they occupy.

An EC declares the label groups it looks at (:attr:`rvmsim.criteria.EcDefinition.groups`);
measurements then read each group inside its *window*, a box that holds every pixel of the
group and the pixels next to them.  Whole-image measurement finds the windows from the label
image (:func:`group_windows`); the fast tuning evaluator derives them from the ISP map
(:class:`rvmsim.pipeline.CandidateEvaluator`).  Both give windows that contain every group
pixel, so a measurement that reads through its windows gives the same value either way.

Convention: a window is ``(x0, y0, x1, y1)`` in output px, ``x1``/``y1`` exclusive; the empty
window is ``(0, 0, 0, 0)``.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from .. import labels as L

__all__ = ["LabelGroup", "Window", "EMPTY_WINDOW", "group_windows", "group_window",
           "unique_groups", "group_chunks", "GROUPS_PER_CHUNK"]

#: ``(x0, y0, x1, y1)``, output px, ``x1`` and ``y1`` exclusive.
Window = tuple[int, int, int, int]
EMPTY_WINDOW: Window = (0, 0, 0, 0)
#: Groups handled together in one pass (one bit, or one byte of a uint64, per group).
GROUPS_PER_CHUNK = 8
#: Block size (px) of the one-pass window search.
_BLOCK = 8


@dataclass(frozen=True)
class LabelGroup:
    """A named set of label ids that an EC reads, e.g. the board or F's stripe and patch.

    Parameters
    ----------
    name : str
        Unique among the groups of the selected ECs; two ECs that read the same pixels share
        one group (same name, same labels).
    labels : tuple of int
        Label ids (:mod:`rvmsim.labels`) in the group.
    upper_region : bool
        The group is only read in the upper region of the image (the top
        ``upper_region_fraction`` of the rows, a criteria option), so the fast evaluator
        remaps nothing of it below them.  The EC itself clips what it reads to those rows
        (:meth:`rvmsim.criteria.MeasureOptions.upper_rows`).
    """

    name: str
    labels: tuple[int, ...]
    upper_region: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError("a label group needs a non-empty name")
        ids = tuple(int(i) for i in self.labels)
        if not ids or any(not 0 <= i <= 255 for i in ids):
            raise ValueError(f"label group {self.name!r}: labels must be ids in 0..255")
        object.__setattr__(self, "labels", ids)

    @functools.cached_property
    def lut(self) -> np.ndarray:
        """255 at the group's labels, 0 elsewhere: ``cv2.LUT(labels, group.lut)`` is its mask."""
        return L.lut(self.labels)


def unique_groups(groups: Iterable[LabelGroup]) -> tuple[LabelGroup, ...]:
    """The groups in first-seen order, each once.

    Raises
    ------
    ValueError
        Two different groups share a name.
    """
    out: dict[str, LabelGroup] = {}
    for g in groups:
        seen = out.setdefault(g.name, g)
        if seen != g:
            raise ValueError(f"two different label groups are named {g.name!r}")
    return tuple(out.values())


def group_chunks(groups: Sequence[LabelGroup]) -> list[tuple[LabelGroup, ...]]:
    """The groups in runs of at most :data:`GROUPS_PER_CHUNK` (one pass each)."""
    n = GROUPS_PER_CHUNK
    return [tuple(groups[i : i + n]) for i in range(0, len(groups), n)]


@functools.lru_cache(maxsize=64)
def _bits_lut(chunk: tuple[LabelGroup, ...]) -> np.ndarray:
    table = np.zeros(256, np.uint8)
    for k, g in enumerate(chunk):
        table[list(g.labels)] |= np.uint8(1 << k)
    return table


def group_windows(labels: np.ndarray, groups: Sequence[LabelGroup]) -> dict[str, Window]:
    """The window of each group in a label image, found in one pass per eight groups.

    The image is mapped to one bit per group (``cv2.LUT``), OR-ed over 8×8 blocks, and a
    group's window is the box of its blocks grown by 1 px (the ring a visibility check
    inspects), so measurements then read only small windows.

    Parameters
    ----------
    labels : (H, W) uint8
    groups : sequence of LabelGroup

    Returns
    -------
    dict
        Group name → window (:data:`EMPTY_WINDOW` where the group has no pixel).
    """

    h, w = labels.shape
    gh, gw = -(-h // _BLOCK), -(-w // _BLOCK)
    out: dict[str, Window] = {}
    for chunk in group_chunks(groups):
        bits = cv2.LUT(labels, _bits_lut(chunk))
        if (gh * _BLOCK, gw * _BLOCK) != (h, w):
            bits = cv2.copyMakeBorder(bits, 0, gh * _BLOCK - h, 0, gw * _BLOCK - w,
                                      cv2.BORDER_CONSTANT, value=0)
        # OR over 8 rows, then over the 8 bytes of each 64-bit word (8 columns)
        # (slices, not ufunc.reduce: numpy reduces short strided axes slowly)
        rows = bits.view(np.uint64).reshape(gh, _BLOCK, gw)
        words = functools.reduce(np.bitwise_or, (rows[:, i] for i in range(_BLOCK)))
        cols = words.view(np.uint8).reshape(gh, gw, 8)
        blocks = functools.reduce(np.bitwise_or, (cols[..., i] for i in range(8)))
        for k, g in enumerate(chunk):
            bx, by, bw, bh = cv2.boundingRect(blocks & np.uint8(1 << k))
            if bw == 0:
                out[g.name] = EMPTY_WINDOW
            else:
                out[g.name] = (max(0, bx * _BLOCK - 1), max(0, by * _BLOCK - 1),
                               min(w, (bx + bw) * _BLOCK + 1), min(h, (by + bh) * _BLOCK + 1))
    return out


def group_window(groups: dict[str, Window], group: LabelGroup | str) -> Window:
    """The window of label group ``group`` (or its name) among ``groups``.

    Raises
    ------
    KeyError
        The group is not one the ECs measured declare.
    """
    name = group if isinstance(group, str) else group.name
    try:
        return groups[name]
    except KeyError:
        raise KeyError(f"label group {name!r} is not declared by the ECs measured") from None
