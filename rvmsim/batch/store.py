"""``sweep.sqlite``: a sweep's settings and every finished design point, as they arrive."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from ..errors import RvmsimError
from ..tune import FolderLock, SqliteStore
from .spec import DesignPoint

__all__ = ["SweepStore", "sweep_lock", "SWEEP_DB"]

#: The sweep's store in its output folder.
SWEEP_DB = "sweep.sqlite"

_SCHEMA = ("CREATE TABLE IF NOT EXISTS points (key TEXT PRIMARY KEY, idx INTEGER, "
           "values_json TEXT NOT NULL, result TEXT NOT NULL, session INTEGER NOT NULL, "
           "finished REAL NOT NULL);")


def sweep_lock(out_dir: str | Path) -> FolderLock:
    """The writer lock of the sweep folder ``out_dir`` (``sweep.lock``, its writer in
    ``sweep.pid``; see :mod:`rvmsim.tune.lock`)."""
    return FolderLock(out_dir, "sweep", "sweep")


class SweepStore(SqliteStore):
    """``sweep.sqlite``: the sweep's settings (meta) and every finished design point (JSON);
    ``readonly`` for reading what a sweep has finished (it changes nothing).

    A point's row keeps the session (1, 2, … for each run of the sweep) that computed it and
    when it finished, so a resumed sweep shows what it did not run again.
    """

    def __init__(self, path: str | Path, *, readonly: bool = False):
        super().__init__(path, _SCHEMA, "sweep", readonly=readonly, tables=("points",))

    def add(self, point: DesignPoint, result: dict[str, Any], session: int) -> None:
        """Store one finished point's result (a JSON-ready dict)."""
        self.write("INSERT OR REPLACE INTO points VALUES (?, ?, ?, ?, ?, ?)",
                   [(point.key, point.index, json.dumps(point.values), json.dumps(result),
                     session, time.time())])

    def done(self) -> dict[str, dict[str, Any]]:
        """Finished points (errors included) by key.

        Raises
        ------
        RvmsimError
            One line naming the point whose stored result is not a JSON object.
        """
        out = {}
        for key, text in self.rows("SELECT key, result FROM points"):
            try:
                result = json.loads(text)
            except (TypeError, ValueError) as err:
                raise RvmsimError(f"{self.path}: points: {key}: result: unreadable "
                                  f"({err})") from None
            if not isinstance(result, dict):
                raise RvmsimError(f"{self.path}: points: {key}: result: not a JSON object")
            out[str(key)] = result
        return out
