"""Run store: a tuning run's settings, state and every evaluated candidate, in one SQLite file.

Trials are written a batch at a time in one transaction (WAL journal), so a run killed at
any moment keeps every completed batch and nothing half-written; a resumed run reads them
back.  Values are JSON text, never pickles.

Tables: ``meta(key, value)`` — the run's :class:`~rvmsim.tune.RunSettings` (``scene``,
``scene_key``, ``vehicle``, ``strategy``, ``seed``, ``budget``, ``criteria_file``,
``config``), its state (``status``, ``stopped``, ``total``) and ``format`` (2; runs of
rvmsim 0.1 have no ``format`` and their settings in ``run.json`` only, see
:mod:`rvmsim.tune.folder`) — and ``trials(idx, stage, params, score, objective, passed,
ec)`` where ``params`` is the JSON of all 14 ISP parameters and ``ec`` maps each EC to
``[value, score, passed]``.
"""

from __future__ import annotations

import json
import sqlite3
from pathlib import Path
from typing import Any

from ..errors import RvmsimError
from ..isp import IspParams
from .records import (
    RunSettings,
    RunState,
    RunStatus,
    StopReason,
    TrialRecord,
    ec_json,
    ecs_from_json,
    json_default,
    params_json,
)

# params_json, ec_json and json_default live in .records (the stored forms of the run model);
# they stay importable from here, where they were first.
__all__ = ["SqliteStore", "RunStore", "RUN_FORMAT", "params_json", "ec_json", "json_default"]

#: ``meta.format`` of the run stores this version writes.
RUN_FORMAT = 2

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

    def _record(self, row: tuple[Any, ...]) -> TrialRecord:
        idx, stage, params, score, objective, passed, ec = row
        return TrialRecord(idx, stage, IspParams(**json.loads(params)), score, objective,
                           bool(passed), ecs_from_json(ec))

    def trials(self, start: int = 0, stop: int | None = None) -> list[TrialRecord]:
        """Trials with ``start <= idx < stop``, in index order."""
        q = "SELECT idx, stage, params, score, objective, passed, ec FROM trials WHERE idx >= ?"
        args: list[Any] = [start]
        if stop is not None:
            q += " AND idx < ?"
            args.append(stop)
        return [self._record(r) for r in self.db.execute(q + " ORDER BY idx", args)]

    def replay(self) -> dict[int, tuple[float, float, IspParams]]:
        """(EC score, objective, parameters) of every trial by index: what a resumed search
        tells its strategy (the ECs are not read)."""
        return {idx: (score, objective, IspParams(**json.loads(params)))
                for idx, params, score, objective in self.db.execute(
                    "SELECT idx, params, score, objective FROM trials ORDER BY idx")}

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

    def scores(self) -> list[float]:
        """Every trial's EC score, in index order."""
        return [float(s) for (s,) in self.db.execute("SELECT score FROM trials ORDER BY idx")]

    # ------------------------------------------------------------------ settings and state
    def write_settings(self, settings: RunSettings) -> None:
        """Record what the run is (once, when it starts, or when an old run is resumed)."""
        self.set_meta(format=RUN_FORMAT, **settings.as_json())

    def settings(self) -> RunSettings | None:
        """The run's settings, or None for a run of rvmsim 0.1 (settings in run.json only).

        Raises
        ------
        RvmsimError
            One line: a store of a newer rvmsim, or unreadable settings.
        """
        meta = self.meta()
        fmt = meta.get("format")
        if fmt is None:
            return None
        if fmt != RUN_FORMAT:
            raise RvmsimError(f"{self.path}: run format {fmt!r} is not {RUN_FORMAT}: written by "
                              "another rvmsim version; use that version to read it")
        try:
            return RunSettings.from_json(meta)
        except (KeyError, TypeError, ValueError) as err:
            msg = f"{self.path}: unreadable run settings ({err}); start a new run"
            raise RvmsimError(" ".join(msg.split())) from None

    def set_state(self, status: RunStatus, stopped: StopReason | None = None,
                  **extra: Any) -> None:
        """Record the run's status (and why it stopped); ``extra``: ``strategy``, ``total``."""
        self.set_meta(status=str(status), stopped=None if stopped is None else str(stopped),
                      **extra)

    def state(self) -> RunState:
        """The run's state; also of a run of rvmsim 0.1, whose status was free text.

        Raises
        ------
        RvmsimError
            One line: no status recorded, or one this version does not know.
        """
        meta = self.meta()
        text = meta.get("status")
        total = meta.get("total")
        strategy = str(meta.get("strategy", "?"))
        total = None if total is None else int(total)
        stopped = meta.get("stopped")
        try:
            if "format" in meta:
                return RunState(RunStatus(str(text)), None if stopped is None else StopReason(stopped),
                                strategy, total)
            return _legacy_state(str(text), strategy, total)
        except ValueError:
            raise RvmsimError(f"{self.path}: unknown run status {text!r} (written by another "
                              "rvmsim version?)") from None


def _legacy_state(text: str, strategy: str, total: int | None) -> RunState:
    """The state of a run of rvmsim 0.1 from its status text: ``running``, ``done``,
    ``stopped (max-time)``, ``stopped (target-score)``,
    ``interrupted (continue with --resume)``; ValueError for anything else."""
    if text.startswith("interrupted"):
        return RunState(RunStatus.INTERRUPTED, None, strategy, total)
    if text.startswith("stopped (") and text.endswith(")"):
        return RunState(RunStatus.DONE, StopReason(text[len("stopped ("):-1]), strategy, total)
    status = RunStatus(text)
    return RunState(status, StopReason.DONE if status is RunStatus.DONE else None, strategy,
                    total)
