"""Storage below every stage: the SQLite file of JSON values both the run store and the
sweep store are (:class:`SqliteStore`), the writer lock of run and sweep folders
(:class:`FolderLock`, :class:`Writer`), the JSON form of numpy scalars
(:func:`json_default`), and output files written whole or not at all
(:func:`staged_folder`, :class:`StagedFiles`, :func:`write_text`, :func:`os_error_text`).

Modules: :mod:`.sqlite`, :mod:`.lock`, :mod:`.jsonable`, :mod:`.files`.  They import nothing
of rvmsim but its errors, so every stage may use them.
"""

from __future__ import annotations

from .files import (StagedFiles, disk_is_full, os_error_text, readable_text, staged_folder,
                    write_problem, write_text)
from .jsonable import json_default
from .lock import FolderLock, Writer
from .sqlite import SqliteStore

__all__ = ["SqliteStore", "FolderLock", "Writer", "json_default", "staged_folder",
           "StagedFiles", "write_text", "readable_text", "os_error_text", "write_problem",
           "disk_is_full"]
