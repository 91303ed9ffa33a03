"""Exceptions rvmsim raises for problems a user can fix (bad files, bad values)."""

from __future__ import annotations

__all__ = ["RvmsimError", "SceneError"]


class RvmsimError(Exception):
    """Base class: the CLI prints these as one line and exits with status 2."""


class SceneError(RvmsimError):
    """A scene file (or a file it names) is unusable.

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
