"""HTML review pages: the page kit, the run report and the validation page."""

from __future__ import annotations

from .run import (
    write_report,
    write_batch_report,
    find_runs,
    EC_GROUP_NAMES,
    SECTION_IDS,
)
from .validation import validation_page, PICTURE_CAPTIONS

__all__ = [
    "write_report",
    "write_batch_report",
    "find_runs",
    "EC_GROUP_NAMES",
    "SECTION_IDS",
    "validation_page",
    "PICTURE_CAPTIONS",
]
