"""HTML review pages: the page kit and the run report."""

from __future__ import annotations

from .run import (
    write_report,
    write_batch_report,
    write_any_report,
    find_runs,
    EC_GROUP_NAMES,
    SECTION_IDS,
)
from .plots import (
    convergence_png,
    histogram_png,
)

__all__ = [
    "write_report",
    "write_batch_report",
    "write_any_report",
    "find_runs",
    "EC_GROUP_NAMES",
    "SECTION_IDS",
    "convergence_png",
    "histogram_png",
]
