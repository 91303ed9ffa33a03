"""``sweep.sqlite``: a sweep's settings, every finished design point and every finished
re-check of one (:mod:`rvmsim.batch.recheck`), as they arrive.

A store made before re-checks existed has no ``rechecks`` table: it reads as having none,
and resuming it adds the table.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import RvmsimError
from ..storage import FolderLock, SqliteStore
from .payloads import PointResult, YieldDoc, YieldError
from .spec import DesignPoint
from .yields import yield_problem

__all__ = ["SweepStore", "sweep_lock", "SWEEP_DB"]

#: The sweep's store in its output folder.
SWEEP_DB = "sweep.sqlite"

_SCHEMA = ("CREATE TABLE IF NOT EXISTS points (key TEXT PRIMARY KEY, idx INTEGER, "
           "values_json TEXT NOT NULL, result TEXT NOT NULL, session INTEGER NOT NULL, "
           "finished REAL NOT NULL);"
           "CREATE TABLE IF NOT EXISTS rechecks (key TEXT NOT NULL, round INTEGER NOT NULL, "
           "idx INTEGER, result TEXT NOT NULL, session INTEGER NOT NULL, "
           "finished REAL NOT NULL, PRIMARY KEY (key, round));")


def sweep_lock(out_dir: str | Path) -> FolderLock:
    """The writer lock of the sweep folder ``out_dir`` (``sweep.lock``, its writer in
    ``sweep.pid``; see :mod:`rvmsim.storage.lock`)."""
    return FolderLock(out_dir, "sweep", "sweep")


def _is_number(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _result_problem(r: object) -> str | None:
    """What is wrong with a stored point result (None: it is one
    :func:`~rvmsim.batch.point.run_point` returns, as far as the outputs read it)."""
    if not isinstance(r, dict):
        return "not a JSON object"
    if "error" in r:
        return None if isinstance(r["error"], str) else "error: not a text"
    kinds: dict[str, Callable[[object], bool]] = {"score": _is_number, "passed": lambda v: isinstance(v, bool),
                             "limiting_ec": lambda v: v is None or isinstance(v, str),
                             "evaluations": lambda v: isinstance(v, int),
                             "ecs": lambda v: isinstance(v, dict) and all(
                                 isinstance(o, dict) and isinstance(o.get("passed"), bool)
                                 for o in v.values()),
                             "params": lambda v: isinstance(v, dict) and all(
                                 _is_number(x) for x in v.values())}
    for key, ok in kinds.items():
        if key not in r:
            return f"no {key}"
        if not ok(r[key]):
            return f"{key}: not what a sweep stores ({str(r[key])[:40]!r})"
    sens = r.get("sensitivity")
    if sens is not None and not (isinstance(sens, dict) and isinstance(sens.get("params"), dict)
                                 and all(isinstance(p, dict) and (p.get("drop_5pct") is None
                                                                   or _is_number(p["drop_5pct"]))
                                         for p in sens["params"].values())):
        return "sensitivity: not what a sweep stores"
    inf = r.get("infeasible", [])  # absent in stores made before the check existed
    if not (isinstance(inf, list) and all(isinstance(x, dict) and isinstance(x.get("ec"), str)
                                          and isinstance(x.get("reason"), str)
                                          and isinstance(x.get("short", ""), str)
                                          for x in inf)):
        return "infeasible: not what a sweep stores"
    if "robustness" in r:  # absent in stores made before yields existed, or without one
        problem = yield_problem(r["robustness"])
        if problem is not None:
            return f"robustness: {problem}"
    return None


class SweepStore(SqliteStore):
    """``sweep.sqlite``: the sweep's settings (meta) and every finished design point (JSON);
    ``readonly`` for reading what a sweep has finished (it changes nothing).

    A point's row keeps the session (1, 2, … for each run of the sweep) that computed it and
    when it finished, so a resumed sweep shows what it did not run again.
    """

    def __init__(self, path: str | Path, *, readonly: bool = False):
        super().__init__(path, _SCHEMA, "sweep", readonly=readonly, tables=("points",))

    def add(self, point: DesignPoint, result: PointResult, session: int) -> None:
        """Store one finished point's result (a JSON-ready dict)."""
        self.write("INSERT OR REPLACE INTO points VALUES (?, ?, ?, ?, ?, ?)",
                   [(point.key, point.index, json.dumps(point.values), json.dumps(result),
                     session, time.time())])

    def sessions(self) -> int:
        """How many sessions have run the sweep so far (0 for a new store).

        Raises
        ------
        RvmsimError
            One line: the stored count is not a whole number.
        """
        n = self.meta().get("sessions", 0)
        if not isinstance(n, int) or isinstance(n, bool) or n < 0:
            raise RvmsimError(f"{self.path}: meta: sessions: {n!r} is not a number of sessions")
        return n

    def add_recheck(self, point: DesignPoint, round_: int, result: PointResult,
                    session: int) -> None:
        """Store one finished re-check (round ``round_`` ≥ 1) of a point."""
        self.write("INSERT OR REPLACE INTO rechecks VALUES (?, ?, ?, ?, ?, ?)",
                   [(point.key, round_, point.index, json.dumps(result), session,
                     time.time())])

    def set_yield(self, point: DesignPoint, round_: int,
                  robustness: YieldDoc | YieldError) -> None:
        """Add a yield (``robustness``) to the stored result of the run of ``point`` from
        round ``round_`` (0: the first pass) that is its best; the row's session and time
        stay (for results stored before yields existed: :func:`~rvmsim.batch.run.run_sweep`
        measures theirs on resume)."""
        table, where, args = (("points", "key = ?", (point.key,)) if round_ == 0 else
                              ("rechecks", "key = ? AND round = ?", (point.key, round_)))
        (text,), = self.rows(f"SELECT result FROM {table} WHERE {where}", args)
        result = {**json.loads(text), "robustness": robustness}
        self.write(f"UPDATE {table} SET result = ? WHERE {where}", [(json.dumps(result), *args)])

    def done(self) -> dict[str, PointResult]:
        """Finished points (errors included) by key.

        Raises
        ------
        RvmsimError
            One line naming the point whose stored result is not a JSON object.
        """
        return {str(key): self._result("points", str(key), text)
                for key, text in self.rows("SELECT key, result FROM points")}

    def rechecks(self) -> dict[tuple[str, int], PointResult]:
        """Finished re-checks (errors included) by (point key, round); none in a store made
        before re-checks existed.

        Raises
        ------
        RvmsimError
            One line naming the point and round whose stored result is not one.
        """
        have = self.rows("SELECT name FROM sqlite_master WHERE type = 'table' AND "
                         "name = 'rechecks'")
        if not have:
            return {}
        out: dict[tuple[str, int], PointResult] = {}
        for key, rnd, text in self.rows("SELECT key, round, result FROM rechecks"):
            if not isinstance(rnd, int) or isinstance(rnd, bool) or rnd < 1:
                raise RvmsimError(f"{self.path}: rechecks: {key}: round: {rnd!r} is not a "
                                  "round number")
            out[(str(key), rnd)] = self._result("rechecks", f"{key} round {rnd}", text)
        return out

    def _result(self, table: str, where: str, text: Any) -> PointResult:
        """A stored result (``text``: the SQLite cell, of any type in a damaged file),
        checked (:func:`_result_problem`)."""
        try:
            result = json.loads(text)
        except (TypeError, ValueError) as err:
            raise RvmsimError(f"{self.path}: {table}: {where}: result: unreadable "
                              f"({err})") from None
        problem = _result_problem(result)
        if problem is not None:
            raise RvmsimError(f"{self.path}: {table}: {where}: result: {problem}")
        return result
