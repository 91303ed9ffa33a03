"""Run store: every evaluated candidate of a tuning run, in one SQLite file.

Trials are written a batch at a time in one transaction (WAL journal), so a run killed at
any moment keeps every completed batch and nothing half-written; a resumed run reads them
back.  Values are JSON text, never pickles.

Tables: ``meta(key, value)`` (scene, config, strategy, seed, status, …) and
``trials(idx, stage, params, score, objective, passed, ec)`` where ``params`` is the JSON of
all 14 ISP parameters and ``ec`` maps each EC to ``[value, score, passed]``.
"""

from __future__ import annotations

import json
import math
import sqlite3
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

from ..errors import RvmsimError
from ..isp import IspParams

__all__ = ["SqliteStore", "RunStore", "TrialRecord", "params_json", "ec_json", "json_default"]

_SCHEMA = """
CREATE TABLE IF NOT EXISTS trials (
    idx INTEGER PRIMARY KEY,
    stage TEXT NOT NULL,
    params TEXT NOT NULL,
    score REAL NOT NULL,
    objective REAL NOT NULL,
    passed INTEGER NOT NULL,
    ec TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS trials_score ON trials (score DESC, idx);
"""


@dataclass(frozen=True)
class TrialRecord:
    """One evaluated candidate."""

    idx: int
    stage: str
    params: IspParams
    score: float
    objective: float
    passed: bool
    ec: dict[str, list[Any]]


def params_json(p: IspParams) -> str:
    """The ``params`` column: all 14 ISP parameters as a JSON object."""
    return json.dumps({n: getattr(p, n) for n in IspParams.names()})


def json_default(o: Any) -> Any:
    """``json.dumps(..., default=json_default)``: numpy scalars (float32, integers) as Python
    numbers.  (Python and float64 NaN never reach ``default``: json writes them itself.)"""
    import numpy as np

    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    raise TypeError(f"{type(o).__name__} is not JSON serializable")


def ec_json(ids: Sequence[str], values: Sequence[float], scores: Sequence[float],
            passed: Sequence[bool]) -> str:
    """The ``ec`` column: each EC (``ids``, the criteria's order) as ``[value, score,
    passed]``, the value ``null`` where it was not measured (NaN)."""
    return json.dumps({e: [None if math.isnan(v) else v, s, ok]
                       for e, v, s, ok in zip(ids, values, scores, passed)})


class SqliteStore:
    """An SQLite file in WAL mode with a ``meta(key, value)`` table of JSON values, plus the
    tables of ``schema``; ``what`` names the kind of database in error messages."""

    def __init__(self, path: str | Path, schema: str, what: str):
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.db = sqlite3.connect(self.path, timeout=30)
            self.db.execute("PRAGMA journal_mode=WAL")
            self.db.executescript(
                "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);"
                + schema)
        except sqlite3.DatabaseError as err:
            raise RvmsimError(f"{self.path}: not a readable {what} database ({err})") from None

    def close(self) -> None:
        self.db.close()

    def set_meta(self, **items: Any) -> None:
        with self.db:
            self.db.executemany(
                "INSERT OR REPLACE INTO meta (key, value) VALUES (?, ?)",
                [(k, json.dumps(v)) for k, v in items.items()],
            )

    def meta(self) -> dict[str, Any]:
        return {k: json.loads(v) for k, v in self.db.execute("SELECT key, value FROM meta")}


class RunStore(SqliteStore):
    """A tuning run's SQLite database (``run.sqlite`` in the run folder)."""

    def __init__(self, path: str | Path):
        super().__init__(path, _SCHEMA, "run")
        self.db.execute("PRAGMA synchronous=NORMAL")

    # ------------------------------------------------------------------ trials
    def add_rows(self, rows: list[tuple[int, str, str, float, float, int, str]]) -> None:
        """Write a batch of already serialised trials atomically: (idx, stage, params JSON,
        score, objective, passed, EC JSON) each."""
        with self.db:
            self.db.executemany(
                "INSERT OR REPLACE INTO trials (idx, stage, params, score, objective, passed, ec)"
                " VALUES (?, ?, ?, ?, ?, ?, ?)",
                rows,
            )

    def count(self) -> int:
        return int(self.db.execute("SELECT COUNT(*) FROM trials").fetchone()[0])

    def _record(self, row: tuple) -> TrialRecord:
        idx, stage, params, score, objective, passed, ec = row
        return TrialRecord(idx, stage, IspParams(**json.loads(params)), score, objective,
                           bool(passed), json.loads(ec))

    def trials(self, start: int = 0, stop: int | None = None) -> list[TrialRecord]:
        """Trials with ``start <= idx < stop``, in index order."""
        q = "SELECT idx, stage, params, score, objective, passed, ec FROM trials WHERE idx >= ?"
        args: list[Any] = [start]
        if stop is not None:
            q += " AND idx < ?"
            args.append(stop)
        return [self._record(r) for r in self.db.execute(q + " ORDER BY idx", args)]

    def top(self, m: int, stage: str | None = None) -> list[TrialRecord]:
        """The ``m`` best trials (highest EC score, then objective, then earliest)."""
        q = "SELECT idx, stage, params, score, objective, passed, ec FROM trials"
        args: list[Any] = []
        if stage is not None:
            q += " WHERE stage = ?"
            args.append(stage)
        q += " ORDER BY score DESC, objective DESC, idx ASC LIMIT ?"
        args.append(m)
        return [self._record(r) for r in self.db.execute(q, args)]

    def best_curve(self) -> list[tuple[int, float, str]]:
        """(idx, best EC score so far, stage) after every trial, for convergence plots."""
        out, best = [], 0.0
        for idx, score, stage in self.db.execute("SELECT idx, score, stage FROM trials ORDER BY idx"):
            best = max(best, score)
            out.append((idx, best, stage))
        return out
