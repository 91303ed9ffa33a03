"""Storage below every stage: the SQLite file of JSON values both the run store and the
sweep store are (:class:`SqliteStore`), the writer lock of run and sweep folders
(:class:`FolderLock`, :class:`Writer`), and the JSON form of numpy scalars
(:func:`json_default`).

Modules: :mod:`.sqlite`, :mod:`.lock`, :mod:`.jsonable`.  They import nothing of rvmsim but
its errors, so every stage may use them.
"""

from __future__ import annotations

from .jsonable import json_default
from .lock import FolderLock, Writer
from .sqlite import SqliteStore

__all__ = ["SqliteStore", "FolderLock", "Writer", "json_default"]
