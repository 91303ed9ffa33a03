"""The one rule by which a search measures at its own size and judges at the RVM image of
record: convert the values measured at the search size into units of record, keep those that
decide the verdict (a clear fail), and measure again at the size of record every candidate
that passes or fails only near its limits (:func:`rvmsim.criteria.could_pass`).

:class:`RecordEvaluator`, :class:`SetEvaluator` and :class:`ImagesEvaluator` (through the
former) all judge by :class:`RecordRule`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..criteria import Criteria, could_pass, pixel_scales, score_batch

__all__ = ["RecordRule"]


@dataclass(frozen=True)
class RecordRule:
    """Values measured at ``search_px`` judged at ``record_px`` (both (W, H) px).

    Convention
    ----------
    Values are rows of ``criteria.ids`` columns, NaN where not measured; pixel-unit ECs
    scale by the ratio of the two sizes (:func:`rvmsim.criteria.pixel_scales`), the others
    stay as measured.
    """

    criteria: Criteria
    search_px: tuple[int, int]
    record_px: tuple[int, int]
    scales: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "scales",
                           pixel_scales(self.criteria, self.search_px, self.record_px))

    @property
    def at_record(self) -> bool:
        """Whether the search measures at the size of record (nothing to convert)."""
        return tuple(self.search_px) == tuple(self.record_px)

    def judge(self, search_values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``search_values`` (n, k) in units of record, and which rows (n,) they do not
        decide: those must be measured at the size of record."""
        values = np.asarray(search_values, dtype=np.float64) * self.scales
        if self.at_record:
            return values, np.zeros(len(values), bool)
        return values, np.asarray(could_pass(score_batch(values, self.criteria)), bool)
