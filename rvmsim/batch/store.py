"""``sweep.sqlite``: a sweep's settings and every finished design point, as they arrive."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from ..tune import SqliteStore
from .spec import DesignPoint

__all__ = ["SweepStore"]


class SweepStore(SqliteStore):
    """``sweep.sqlite``: the sweep's settings (meta) and every finished design point (JSON).

    A point's row keeps the session (1, 2, … for each run of the sweep) that computed it and
    when it finished, so a resumed sweep shows what it did not run again.
    """

    def __init__(self, path: str | Path):
        super().__init__(path, "CREATE TABLE IF NOT EXISTS points (key TEXT PRIMARY KEY, "
                               "idx INTEGER, values_json TEXT NOT NULL, result TEXT NOT NULL, "
                               "session INTEGER NOT NULL, finished REAL NOT NULL);", "sweep")

    def add(self, point: DesignPoint, result: dict[str, Any], session: int) -> None:
        """Store one finished point's result (a JSON-ready dict)."""
        with self.db:
            self.db.execute("INSERT OR REPLACE INTO points VALUES (?, ?, ?, ?, ?, ?)",
                            (point.key, point.index, json.dumps(point.values),
                             json.dumps(result), session, time.time()))

    def done(self) -> dict[str, dict[str, Any]]:
        """Finished points (errors included) by key."""
        return {k: json.loads(r) for k, r in self.db.execute("SELECT key, result FROM points")}
