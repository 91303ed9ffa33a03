"""Run store: a tuning run's settings, state and every evaluated candidate, in one SQLite file.

Trials are written a batch at a time in one transaction (WAL journal), so a run killed at
any moment keeps every completed batch and nothing half-written; a resumed run reads them
back.  Values are JSON text, never pickles.

Tables: ``meta(key, value)`` — the run's :class:`~rvmsim.runs.RunSettings` (``scene``,
``scene_key``, ``vehicle``, ``strategy``, ``seed``, ``budget``, ``criteria_file``,
``config``), its state (``status``, ``stopped``, ``total``) and ``format`` (2; runs of
rvmsim 0.1 have no ``format`` and their settings in ``run.json`` only, see
:mod:`rvmsim.runs.folder`) — and ``trials(idx, stage, params, score, objective, passed,
ec)`` where ``params`` is the JSON of all 14 ISP parameters and ``ec`` maps each EC to
``[value, score, passed]``; ``meta.space`` records the search space (since the diverse
top-M, :mod:`rvmsim.runs.diverse`, measures distances in it); a multi-member run (shared or robust tuning) also has
``members(idx, member, score, objective, passed, ec)``: each member's own results of a
trial (member = its index in the run settings' scenes).
"""

from __future__ import annotations

import dataclasses
import json
import sqlite3
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import RvmsimError
from ..isp import IspParams
from ..search.space import ParamRange, SearchSpace
from ..storage import SqliteStore
from .records import (
    RunSettings,
    RunState,
    EcOutcome,
    RunStatus,
    StopReason,
    TrialRecord,
    ecs_from_json,
)

__all__ = ["RunStore", "RUN_FORMAT"]

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

#: Each member's own results of a multi-member run (shared or robust tuning), made with its
#: first trials: a one-scene run has no such table.
_MEMBERS_SCHEMA = """
CREATE TABLE IF NOT EXISTS members (
    idx INTEGER NOT NULL,
    member INTEGER NOT NULL,
    score REAL NOT NULL,
    objective REAL NOT NULL,
    passed INTEGER NOT NULL,
    ec TEXT NOT NULL,
    PRIMARY KEY (idx, member)
);
"""


class RunStore(SqliteStore):
    """A tuning run's SQLite database (``run.sqlite`` in the run folder); ``readonly`` for
    the readers (see :class:`SqliteStore`)."""

    def __init__(self, path: str | Path, *, readonly: bool = False):
        super().__init__(path, _SCHEMA, "run", readonly=readonly, tables=("trials",))
        self._members_table: bool | None = None
        if not readonly:
            self.db.execute("PRAGMA synchronous=NORMAL")

    # ------------------------------------------------------------------ trials
    def add_rows(self, rows: list[tuple[int, str, str, float, float, int, str]],
                 member_rows: Sequence[tuple[int, int, float, float, int, str]] = ()) -> None:
        """Write a batch of already serialised trials atomically: (idx, stage, params JSON,
        score, objective, passed, EC JSON) each, and with them their members' results
        (idx, member, score, objective, passed, EC JSON) in the same transaction."""
        more: list[tuple[str, Sequence[Sequence[Any]]]] = []
        if member_rows:
            if not self._has_members:
                try:
                    self.db.executescript(_MEMBERS_SCHEMA)
                except sqlite3.DatabaseError as err:
                    raise self._unreadable(err) from None
                self._has_members = True
            more.append(("INSERT OR REPLACE INTO members (idx, member, score, objective, "
                         "passed, ec) VALUES (?, ?, ?, ?, ?, ?)", member_rows))
        self.write("INSERT OR REPLACE INTO trials (idx, stage, params, score, objective, "
                   "passed, ec) VALUES (?, ?, ?, ?, ?, ?, ?)", rows, *more)

    @property
    def _has_members(self) -> bool:
        if self._members_table is None:
            self._members_table = bool(self.rows(
                "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'members'"))
        return self._members_table

    @_has_members.setter
    def _has_members(self, value: bool) -> None:
        self._members_table = value

    def member_table(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Every member result at once: trial index, member, EC score and passed, (n,)
        arrays each (empty for a one-scene run)."""
        if not self._has_members:
            z = np.zeros(0)
            return z.astype(np.int64), z.astype(np.int64), z, z.astype(bool)
        rows = self.rows("SELECT idx, member, score, passed FROM members")
        arr = np.array(rows, dtype=np.float64).reshape(-1, 4)
        return (arr[:, 0].astype(np.int64), arr[:, 1].astype(np.int64), arr[:, 2],
                arr[:, 3].astype(bool))

    def member_results(self, idx: int) -> list[tuple[float, float, bool, dict[str, EcOutcome]]]:
        """Each member's (EC score, objective, passed, ECs) of trial ``idx``, in member
        order; empty for a one-scene run (or a trial without them)."""
        if not self._has_members:
            return []
        out = []
        for member, score, objective, passed, ec in self.rows(
                "SELECT member, score, objective, passed, ec FROM members WHERE idx = ? "
                "ORDER BY member", (idx,)):
            try:
                ecs = ecs_from_json(ec)
            except (TypeError, ValueError, AttributeError) as err:
                raise RvmsimError(" ".join(f"{self.path}: members: trial {idx} member "
                                           f"{member}: ec: unreadable ({err})".split())) from None
            out.append((self._number(idx, "score", score),
                        self._number(idx, "objective", objective), bool(passed), ecs))
        return out

    def count(self) -> int:
        return int(self.rows("SELECT COUNT(*) FROM trials")[0][0])

    def _params(self, idx: object, text: Any) -> IspParams:  # a raw SQLite cell
        """A ``params`` cell as parameters; RvmsimError naming the trial if it is not the
        JSON of all 14 valid parameters."""
        try:
            doc = json.loads(text)
            if not isinstance(doc, dict) or set(doc) != set(IspParams.names()):
                raise ValueError("not an object of the 14 ISP parameters")
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                       for v in doc.values()):
                raise ValueError("a value is not a number")
            return IspParams(**doc)
        except (TypeError, ValueError) as err:
            raise self._bad_cell(idx, "params", err) from None

    def _bad_cell(self, idx: object, column: str, err: Exception) -> RvmsimError:
        return RvmsimError(" ".join(f"{self.path}: trials: trial {idx}: {column}: unreadable "
                                    f"({err})".split()))

    def _number(self, idx: object, column: str, value: object) -> float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        raise self._bad_cell(idx, column, ValueError(f"{str(value)[:40]!r} is not a number"))

    def _record(self, row: tuple[Any, ...]) -> TrialRecord:  # raw SQLite cells
        idx, stage, params, score, objective, passed, ec = row
        try:
            ecs = ecs_from_json(ec)
        except (TypeError, ValueError, AttributeError) as err:
            raise self._bad_cell(idx, "ec", err) from None
        return TrialRecord(int(idx), str(stage), self._params(idx, params),
                           self._number(idx, "score", score),
                           self._number(idx, "objective", objective), bool(passed), ecs)

    def trials(self, start: int = 0, stop: int | None = None) -> list[TrialRecord]:
        """Trials with ``start <= idx < stop``, in index order."""
        q = "SELECT idx, stage, params, score, objective, passed, ec FROM trials WHERE idx >= ?"
        args: list[int | str] = [start]
        if stop is not None:
            q += " AND idx < ?"
            args.append(stop)
        return [self._record(r) for r in self.rows(q + " ORDER BY idx", args)]

    def replay(self) -> dict[int, tuple[float, float, IspParams]]:
        """(EC score, objective, parameters) of every trial by index: what a resumed search
        tells its strategy (the ECs are not read)."""
        return {int(idx): (self._number(idx, "score", score),
                           self._number(idx, "objective", objective), self._params(idx, params))
                for idx, params, score, objective in self.rows(
                    "SELECT idx, params, score, objective FROM trials ORDER BY idx")}

    def top(self, m: int, stage: str | None = None) -> list[TrialRecord]:
        """The ``m`` best trials (highest EC score, then objective, then earliest)."""
        q = "SELECT idx, stage, params, score, objective, passed, ec FROM trials"
        args: list[int | str] = []
        if stage is not None:
            q += " WHERE stage = ?"
            args.append(stage)
        q += " ORDER BY score DESC, objective DESC, idx ASC LIMIT ?"
        args.append(m)
        return [self._record(r) for r in self.rows(q, args)]

    def vectors(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                     np.ndarray, np.ndarray]:
        """Every trial as arrays, for choosing among all of them at once (the ECs are not
        read): index, EC score, objective, passed, and the values of the parameters
        ``names`` (one row per trial, one column per name), in index order."""
        rows = self.rows("SELECT idx, params, score, objective, passed FROM trials ORDER BY idx")
        n = len(rows)
        idx, score, objective = np.empty(n, np.int64), np.empty(n), np.empty(n)
        passed, x = np.empty(n, bool), np.empty((n, len(names)))
        for i, (k, params, sc, obj, ok) in enumerate(rows):
            try:
                doc = json.loads(params)
                x[i] = [float(doc[name]) for name in names]
            except (TypeError, ValueError, KeyError) as err:
                raise self._bad_cell(k, "params", err) from None
            idx[i], passed[i] = int(k), bool(ok)
            score[i], objective[i] = self._number(k, "score", sc), self._number(k, "objective", obj)
        return idx, score, objective, passed, x

    def trials_at(self, idxs: Sequence[int]) -> list[TrialRecord]:
        """The trials of the indices ``idxs``, in that order (missing ones left out)."""
        if not idxs:
            return []
        marks = ", ".join("?" * len(idxs))
        found = {r.idx: r for r in (self._record(row) for row in self.rows(
            "SELECT idx, stage, params, score, objective, passed, ec FROM trials WHERE idx "
            f"IN ({marks})", [int(i) for i in idxs]))}
        return [found[int(i)] for i in idxs if int(i) in found]

    def best_curve(self) -> list[tuple[int, float, str]]:
        """(idx, best EC score so far, stage) after every trial, for convergence plots."""
        out, best = [], 0.0
        for idx, score, stage in self.rows("SELECT idx, score, stage FROM trials ORDER BY idx"):
            best = max(best, self._number(idx, "score", score))
            out.append((idx, best, stage))
        return out

    def scores(self) -> list[float]:
        """Every trial's EC score, in index order."""
        return [self._number(idx, "score", s)
                for idx, s in self.rows("SELECT idx, score FROM trials ORDER BY idx")]

    # ------------------------------------------------------------------ settings and state
    def space(self) -> SearchSpace | None:
        """The search space the run recorded (None: a run of an earlier version, which
        recorded none).

        Raises
        ------
        RvmsimError
            One line: a recorded space that cannot be read.
        """
        doc = self.meta().get("space")
        if doc is None:
            return None
        try:
            return SearchSpace(tuple(ParamRange(**r) for r in doc["ranges"]),
                               IspParams(**doc["base"]))
        except (TypeError, ValueError, KeyError) as err:
            raise RvmsimError(" ".join(f"{self.path}: meta: space: unreadable "
                                       f"({err})".split())) from None

    def begin(self, settings: RunSettings, space: SearchSpace, total: int | None) -> None:
        """Record, in one transaction, that the run starts or resumes: status running, its
        strategy and planned evaluations (``total``; None: unknown), its settings (a resumed
        run of rvmsim 0.1 gets them here) and the search space its diverse top-M measures
        distances in."""
        self.set_meta(status=str(RunStatus.RUNNING), stopped=None, total=total,
                      format=RUN_FORMAT, **settings.as_json(), space=_space_json(space))

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
        if total is not None and (not isinstance(total, int) or isinstance(total, bool)
                                  or total < 0):
            raise RvmsimError(f"{self.path}: meta: total: {total!r} is not a number of "
                              "evaluations")
        stopped = meta.get("stopped")
        try:
            if "format" in meta:
                return RunState(RunStatus(str(text)), None if stopped is None else StopReason(stopped),
                                strategy, total)
            return _legacy_state(str(text), strategy, total)
        except ValueError:
            raise RvmsimError(f"{self.path}: meta: status: unknown run status {text!r} (stopped "
                              f"{stopped!r}; written by another rvmsim version?)") from None


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


def _space_json(space: SearchSpace) -> dict[str, Any]:
    """``meta.space``: the space's ranges and the values of its untuned parameters."""
    return {"ranges": [dataclasses.asdict(r) for r in space.ranges],
            "base": {n: getattr(space.base, n) for n in IspParams.names()}}
