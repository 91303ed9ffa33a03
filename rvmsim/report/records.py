"""Reading what other commands wrote, for the sign-off page and the run report:
``robustness.json`` (``rvmsim robustness``), ``validation.json`` / ``summary.json``
(``rvmsim validate``), ``eol.json`` (``rvmsim eol``), and a sign-off's own ``signoff.json``.

Each reader checks the keys the pages use and raises :class:`~rvmsim.errors.RvmsimError`
with one line naming the file (and the key) when the folder holds no such file, the file is
not JSON, or a key is missing or of the wrong kind.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._io import FilePathText, read_json_file, validate_document
from ..eol.result_file import EolFile
from ..errors import ResultFileError, RvmsimError
from ..isp import IspParams
from ..robust.result_file import RobustnessFile, YieldEstimateDoc
from ..validate.result_file import ValidationFile, ValidationSummaryFile

__all__ = ["RobustnessRecord", "ValidationRecord", "EolRecord", "load_robustness",
           "load_validation", "load_eol", "read_json", "same_setting", "SIGNOFF_JSON",
           "signoff_files", "known_yield", "KnownYield"]

#: What the sign-off writes beside signoff.html.
SIGNOFF_JSON = "signoff.json"


def read_json(path: Path, what: str) -> Any:
    """The JSON document in ``path``, read within the JSON limits
    (:func:`rvmsim._io.read_json_file`); one-line :class:`RvmsimError` naming it otherwise
    (``what``: the command that writes it, for the message)."""
    if not path.is_file():
        where = path.parent
        raise RvmsimError(f"{path}: not found ({where} is not a folder {what} wrote)"
                          if where.is_dir() else f"{where}: no such folder")
    return read_json_file(path, ResultFileError, what=f"{what} result")


@dataclass(frozen=True)
class RobustnessRecord:
    """A ``robustness.json``: ``doc`` as read, checked for the keys the pages use."""

    folder: Path
    path: Path
    doc: dict[str, Any]

    @property
    def yield_(self) -> float:
        return float(self.doc["yield"])

    @property
    def ci(self) -> tuple[float, float]:
        lo, hi = self.doc["ci95"]
        return float(lo), float(hi)

    @property
    def inputs(self) -> dict[str, Any]:
        """What the run recorded of its inputs (empty for a file of an earlier rvmsim)."""
        v = self.doc.get("inputs")
        return v if isinstance(v, dict) else {}

    @property
    def failing(self) -> list[dict[str, Any]]:
        """The samples that fail (after compensation, when it was judged)."""
        return [s for s in self.doc["samples"] if not s.get("passed", True)]


def load_robustness(folder: str | Path) -> RobustnessRecord:
    """The ``robustness.json`` in ``folder`` (see the module docstring for the errors)."""
    folder = Path(folder)
    path = folder / "robustness.json"
    doc = validate_document(RobustnessFile, read_json(path, "rvmsim robustness"), str(path),
                            ResultFileError)
    return RobustnessRecord(folder, path, doc)


@dataclass(frozen=True)
class ValidationRecord:
    """A validation folder: one capture's ``validation.json`` or several captures'
    ``summary.json`` (rows), and the file read."""

    folder: Path
    path: Path
    single: dict[str, Any] | None
    rows: list[dict[str, Any]]


def load_validation(folder: str | Path) -> ValidationRecord:
    """The validation ``rvmsim validate`` wrote into ``folder``."""
    folder = Path(folder)
    single, several = folder / "validation.json", folder / "summary.json"
    if several.is_file():
        rows = validate_document(ValidationSummaryFile, read_json(several, "rvmsim validate"),
                                 str(several), ResultFileError)
        return ValidationRecord(folder, several, None, rows)
    doc = validate_document(ValidationFile, read_json(single, "rvmsim validate"), str(single),
                            ResultFileError)
    return ValidationRecord(folder, single, doc, [])


@dataclass(frozen=True)
class EolRecord:
    """An ``eol.json`` (``rvmsim eol``)."""

    folder: Path
    path: Path
    doc: dict[str, Any]


def load_eol(folder: str | Path) -> EolRecord:
    """The ``eol.json`` in ``folder``."""
    folder = Path(folder)
    path = folder / "eol.json"
    doc = validate_document(EolFile, read_json(path, "rvmsim eol"), str(path), ResultFileError)
    return EolRecord(folder, path, doc)


def same_setting(isp: Mapping[str, Any], values: Mapping[str, Any]) -> bool:
    """Whether a recorded setting (``isp`` of a JSON file) has the 14 values of ``values``
    (a params dict), to a relative 1e-9."""

    try:
        return all(math.isclose(float(isp[n]), float(values[n]), rel_tol=1e-9, abs_tol=1e-12)
                   for n in IspParams.names())
    except (KeyError, TypeError, ValueError):
        return False


def signoff_files(run_dir: Path) -> tuple[Path, Path] | None:
    """The sign-off (signoff.html, signoff.json) written into the run folder or its
    ``signoff/`` folder, None when there is none."""
    for folder in (run_dir, run_dir / "signoff"):
        html, js = folder / "signoff.html", folder / SIGNOFF_JSON
        if html.is_file():
            return html, js
    return None


class _KnownYieldDoc(YieldEstimateDoc):
    """What :func:`known_yield` reads of a robustness.json, or of a signoff.json's
    ``robustness``."""

    isp: dict[str, Any]
    yield_before_compensation: YieldEstimateDoc | None = None
    path: FilePathText | None = None


@dataclass(frozen=True)
class KnownYield:
    """A yield measured for a setting: the estimate's JSON form (yield, ci95, n_pass, n),
    the one before compensation (None without), and the file it was read from."""

    estimate: dict[str, Any]
    before: dict[str, Any] | None
    source: Path


def known_yield(run_dir: Path, values: Mapping[str, Any]) -> KnownYield | None:
    """The yield of the setting ``values`` recorded in or beside the run: a sign-off's
    ``signoff.json``, else a ``robustness.json`` in a folder of the run; only one that
    judged these 14 values counts.  Unreadable files are passed over (this is a report's
    note, not an input)."""
    found = signoff_files(run_dir)
    candidates = [] if found is None else [found[1]]
    candidates += sorted(run_dir.glob("*/robustness.json")) + [run_dir / "robustness.json"]
    for path in candidates:
        rob: dict[str, Any]
        try:
            doc = read_json_file(path, ResultFileError)
            rob = validate_document(_KnownYieldDoc, doc.get("robustness") if (
                path.name == SIGNOFF_JSON and isinstance(doc, dict)) else doc, str(path),
                ResultFileError)
        except RvmsimError:  # absent or unreadable: not a result to report
            continue
        if not same_setting(rob["isp"], values):
            continue
        before = rob.get("yield_before_compensation")
        source = Path(rob.get("path", path)) if path.name == SIGNOFF_JSON else path
        return KnownYield(rob, before if isinstance(before, dict) else None, source)
    return None
