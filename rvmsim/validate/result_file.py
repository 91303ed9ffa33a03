"""The schemas of what ``rvmsim validate`` writes, as ``rvmsim signoff`` reads it back: one
capture's ``validation.json`` (:meth:`~rvmsim.validate.Validation.to_dict`) and several
captures' ``summary.json`` (:meth:`~rvmsim.validate.captures.CaptureOutcome.row`).  Only the
keys the readers use are described; other keys are allowed.
``tests/bad_input/test_result_files.py`` checks that what the writers write validates."""

from __future__ import annotations

from pydantic import RootModel

from .._io import FilePathText, ReadModel

__all__ = ["ValidationFile", "ValidationSummaryFile"]


class _Check(ReadModel):
    name: str = ""
    value: float | None = None
    limit: float | None = None
    hint: str = ""
    passed: bool = False


class ValidationFile(ReadModel):
    """``validation.json``: one capture's verdict and its checks."""

    scene: str = ""
    capture: FilePathText
    passed: bool
    checks: list[_Check]


class _SummaryRow(ReadModel):
    capture: FilePathText | None = None
    verdict: str
    error: str | None = None


class ValidationSummaryFile(RootModel[list[_SummaryRow]]):
    """``summary.json``: one row per capture."""
