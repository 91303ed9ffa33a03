"""An SQLite file of JSON values, shared by the run store (``run.sqlite``,
:class:`rvmsim.runs.RunStore`) and the sweep store (``sweep.sqlite``,
:class:`rvmsim.batch.SweepStore`): WAL journal, one transaction per write, read-only opening
that leaves nothing behind, and one-line errors for a file that is not such a database."""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Any, Sequence

from ..errors import RvmsimError
from .files import disk_is_full

__all__ = ["SqliteStore"]


class SqliteStore:
    """An SQLite file in WAL mode with a ``meta(key, value)`` table of JSON values, plus the
    tables of ``schema``; ``what`` names the kind of database in error messages.

    ``readonly`` opens an existing file for reading only (``status``, ``select``,
    ``report``): nothing is created or written, not even a schema into an empty file, and
    the ``tables`` it must hold are checked.  A file without a ``-wal`` beside it has no
    writer (a writer keeps one while it writes, and a killed one leaves it), so it is opened
    immutable, which makes SQLite leave no ``-wal``/``-shm`` files behind either.

    Every query raises :class:`~rvmsim.errors.RvmsimError` (one line naming the file) for a
    file that is not such a database: junk, truncated, missing tables, unreadable rows.
    """

    def __init__(self, path: str | Path, schema: str, what: str, *, readonly: bool = False,
                 tables: tuple[str, ...] = ()):
        self.path = Path(path)
        self.what = what
        try:
            if readonly:
                self.db = sqlite3.connect(_readonly_uri(self.path), uri=True, timeout=30)
            else:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self.db = sqlite3.connect(self.path, timeout=30)
                self.db.execute("PRAGMA journal_mode=WAL")
                self.db.executescript(
                    "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
                    + schema)
        except sqlite3.DatabaseError as err:
            raise self._unreadable(err) from None
        if readonly:
            have = {name for (name,) in self.rows("SELECT name FROM sqlite_master WHERE "
                                                  "type = 'table'")}
            missing = [t for t in ("meta", *tables) if t not in have]
            if missing:
                self.db.close()
                raise RvmsimError(f"{self.path}: not a {what} database (no table "
                                  f"{', '.join(missing)})")

    def _unreadable(self, err: Exception) -> RvmsimError:
        if _full_disk(err, self.path):
            return RvmsimError(f"{self.path}: the disk is full ({err})")
        return RvmsimError(" ".join(
            f"{self.path}: not a readable {self.what} database ({err})".split()))

    def rows(self, sql: str, args: Sequence[Any] = ()) -> list[tuple[Any, ...]]:
        """The rows of one query; RvmsimError for a file that is not a readable database."""
        try:
            return self.db.execute(sql, args).fetchall()
        except sqlite3.DatabaseError as err:
            raise self._unreadable(err) from None

    def write(self, sql: str, rows: Sequence[Sequence[Any]],
              *more: tuple[str, Sequence[Sequence[Any]]]) -> None:
        """Run one statement for every row (and each further ``(statement, rows)``) in one
        transaction; RvmsimError (one line) where the database cannot be written (full
        disk, read-only file, junk)."""
        try:
            with self.db:
                self.db.executemany(sql, rows)
                for q, r in more:
                    self.db.executemany(q, r)
        except sqlite3.DatabaseError as err:
            if _full_disk(err, self.path):
                raise RvmsimError(f"{self.path}: the disk is full ({err})") from None
            raise RvmsimError(f"{self.path}: cannot write the {self.what} database "
                              f"({err})") from None

    def close(self) -> None:
        self.db.close()

    def set_meta(self, **items: Any) -> None:
        self.write("INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)",
                   [(k, json.dumps(v)) for k, v in items.items()])

    def meta(self) -> dict[str, Any]:
        out = {}
        for key, value in self.rows("SELECT key, value FROM meta"):
            try:
                out[str(key)] = json.loads(value)
            except (TypeError, ValueError):
                raise RvmsimError(f"{self.path}: meta: {key}: not a JSON value "
                                  f"({str(value)[:40]!r})") from None
        return out


def _full_disk(err: Exception, path: Path) -> bool:
    """Whether SQLite's ``err`` comes of a full disk: SQLite says so ("database or disk is
    full"), or says "disk I/O error" while the disk holding ``path`` has (almost) no free
    space (:func:`~.files.disk_is_full`)."""
    text = str(err).lower()
    if "disk is full" in text:
        return True
    return "disk i/o error" in text and disk_is_full(path)


def _readonly_uri(path: Path) -> str:
    """The URI SQLite opens ``path`` read-only with (immutable when no ``-wal`` is beside
    it: see :class:`SqliteStore`)."""
    if not path.is_file():
        raise sqlite3.OperationalError("no such file")
    wal = path.with_name(path.name + "-wal")
    return path.resolve().as_uri() + ("?mode=ro" if wal.exists() else "?mode=ro&immutable=1")
