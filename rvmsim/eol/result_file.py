"""The schema of ``eol.json`` (:meth:`~rvmsim.eol.records.StationResult.as_dict`) as
``rvmsim signoff`` reads it back: the keys and types its readers use (a key with a default may
be absent; other keys are allowed).  ``tests/bad_input/test_result_files.py`` checks that what
``rvmsim eol`` writes validates."""

from __future__ import annotations

from typing import Any

from .._io import FilePathText, ReadModel

__all__ = ["EolFile"]


class _CarRow(ReadModel):
    capture: FilePathText = ""
    name: str = ""
    verdict: str
    reasons: list[str] = []
    status: str = ""
    guidelines: dict[str, Any] | None = None


class EolFile(ReadModel):
    """``eol.json``: the station's run of every car."""

    scene: str = ""
    params_file: FilePathText
    platform_isp: dict[str, Any] = {}
    cars: int
    passed: int
    results: list[_CarRow]
    guidelines: dict[str, Any] | None = None
