"""Exceptions rvmsim raises for problems a user can fix (bad files, bad values).

Every file kind has its own class so that callers (and the CLI) can tell a bad scene from a
bad criteria or tuning file; all of them are :class:`InputFileError`, which carries the file,
the dotted key and the line, and all are :class:`RvmsimError`, which the CLI prints as one
line before exiting with status 2.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "RvmsimError",
    "InputFileError",
    "SceneError",
    "CriteriaError",
    "TuningConfigError",
    "SweepFileError",
    "ParamsFileError",
    "VariationError",
    "CompensationError",
    "ResultFileError",
]


class RvmsimError(Exception):
    """Base class: the CLI prints these as one line and exits with status 2."""


class InputFileError(RvmsimError):
    """A user file (or a file it names) is unusable.

    Parameters
    ----------
    file : str
        The file at fault.
    key : str
        Dotted path of the offending key (``camera.intrinsics.fx``), or "" for the whole file.
    message : str
        What is wrong, and where useful what was found.
    line : int or None
        1-based line in ``file`` where the key stands, when known.
    """

    def __init__(self, file: str, key: str, message: str, line: int | None = None):
        self.file = str(file)
        self.key = key
        self.message = message
        self.line = line
        where = self.file if line is None else f"{self.file}:{line}"
        text = f"{where}: {key}: {message}" if key else f"{where}: {message}"
        super().__init__(text)

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        # by its parameters: a worker process's error reaches the parent whole
        return (type(self), (self.file, self.key, self.message, self.line))


class SceneError(InputFileError):
    """A scene file, or a mesh file it names, is unusable."""


class CriteriaError(InputFileError):
    """A criteria file is unusable."""


class TuningConfigError(InputFileError):
    """A tuning config file (``--config``) is unusable."""


class SweepFileError(InputFileError):
    """A sweep file is unusable."""


class ParamsFileError(InputFileError):
    """An ISP params file is unusable."""


class VariationError(InputFileError):
    """A variation file (``--variation``), or a scene's ``variation`` section, is unusable."""


class CompensationError(InputFileError):
    """A compensation file (``--compensation``), or a ``compensation`` section, is unusable."""


class ResultFileError(InputFileError):
    """A file an rvmsim command wrote and another reads back (``run.json``,
    ``robustness.json``, ``eol.json``, …) is unusable: over the JSON limits, not JSON, or not
    of its schema (damaged, or edited by hand)."""
