"""The RVM image of record: the size every verdict refers to, whatever size a search measures at.

A pixel-unit EC ("2-3 ≤ 5 px") means pixels of the image the car shows: the display output of
record, :attr:`rvmsim.scene.Display.rvm_image_px` (default 1280 × 720; the scene's ``display``
section wins over the criteria file's).  A search may measure at another size (a tuning
config's ``output.size``, a test's small image).  Then:

1. its pixel-unit values are converted to pixels of record (:func:`to_record_units`: a length
   along x scales with the widths, along y with the heights; the EC says which,
   :attr:`rvmsim.criteria.EcDefinition.pixel_axis`), so scores and limits mean the same at
   every size;
2. a candidate that passes, or fails only *near* its limits, is measured again at the size of
   record, and that measurement is its result (:func:`could_pass` picks them): quantisation
   at a smaller size moves a value by a pixel or two, so a converted value alone cannot decide
   a pass.  Near means every enabled EC either passes or scores at least
   :data:`NEAR_SCORE` (a graded EC's sigmoid, in the units of record); an EC that is binary or
   not measured and fails is not near.  With the paper's sigmoids :data:`NEAR_SCORE` covers
   at least two pixels of the search size beyond every limit.

:func:`rvmsim.pipeline.make_evaluator` does both, so every evaluator's verdict is the verdict
at the size of record.  Measuring at the size of record from the start needs neither step.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .scoring import Criteria, EcBatch
from ..scene import Display

if TYPE_CHECKING:
    from ..scene import Scene

__all__ = ["NEAR_SCORE", "record_size", "record_display", "pixel_scales", "to_record_units",
           "could_pass"]

#: A failing graded EC whose score (in units of record) is at least this is near its limit:
#: the candidate is measured again at the size of record.  0.005 is ≥ 2 px of a 640 × 360
#: search beyond the limits of every one of the paper's ECs (3-1: 4 px of record → 0.023;
#: 2-3: 4 px → 0.009; 2-1: 0.56 % → 0.16; 4-1: 0.07 → 0.05).
NEAR_SCORE = 0.005


def record_display(criteria: Criteria, scene: Scene | None = None) -> Display:
    """The display whose RVM image is of record: the scene's ``display`` section, else the
    criteria file's, else the defaults."""

    return (scene.display if scene is not None else None) or criteria.display or Display()


def record_size(criteria: Criteria, scene: Scene | None = None) -> tuple[int, int]:
    """(width, height) px of the RVM image of record (:func:`record_display`'s
    ``rvm_image_px``)."""
    w, h = record_display(criteria, scene).rvm_image_px
    return int(w), int(h)


def pixel_scales(criteria: Criteria, measured: tuple[int, int],
                 record: tuple[int, int]) -> np.ndarray:
    """Per EC in ``criteria.ids`` order: px of record per measured px for ``"px"`` ECs (by
    their :attr:`~rvmsim.criteria.EcDefinition.pixel_axis`; both axes: the geometric mean),
    1 for every other unit.  ``measured`` and ``record`` are (width, height) px."""
    sx, sy = record[0] / measured[0], record[1] / measured[1]
    by_axis = {"x": sx, "y": sy, "": math.sqrt(sx * sy)}
    return np.array([by_axis[ec.pixel_axis] if ec.unit == "px" else 1.0
                     for ec in criteria.ecs], np.float64)


def to_record_units(values: np.ndarray, criteria: Criteria, measured: tuple[int, int],
                    record: tuple[int, int]) -> np.ndarray:
    """Values measured at ``measured`` (W, H) px in units of record: (n, k) or (k,) in
    ``criteria.ids`` order, NaN kept."""
    if tuple(measured) == tuple(record):
        return values
    return np.asarray(values, np.float64) * pixel_scales(criteria, measured, record)


def could_pass(batch: EcBatch) -> np.ndarray:
    """Which candidates (rows of ``batch``, scored in units of record) pass or fail only near
    their limits, (n,) bool: those a measurement at the size of record must decide."""
    ok = batch.passed | (batch.scores >= NEAR_SCORE) | ~batch.enabled
    return np.asarray(np.all(ok, axis=1))
