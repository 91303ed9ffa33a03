"""Reading a run folder: its store, its settings (also of runs of rvmsim 0.1), what
``rvmsim status`` and ``rvmsim select`` print.

A run folder holds ``run.sqlite`` (the truth: settings, state, trials), ``run.json`` (a
human-readable export of the settings), ``top/`` and ``best/``.  Runs written by rvmsim 0.1
kept their settings in ``run.json`` only and their status as free text; they are read as they
are (:func:`run_settings`), and a resumed one is brought to the current format.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

from ..errors import RvmsimError
from ..isp import OutputSpec, params_to_dict
from .lock import FolderLock
from .records import RunSettings, RunState, RunStatus, TrialRecord
from .store import RunStore

__all__ = ["open_run", "run_settings", "run_state", "run_lock", "find_runs", "is_run_folder",
           "status_lines", "rank_text", "rank_params_text"]

RUN_DB = "run.sqlite"
RUN_JSON = "run.json"


def run_lock(run_dir: str | Path) -> FolderLock:
    """The writer lock of the run folder ``run_dir`` (``run.lock``, its writer in
    ``run.pid``; see :mod:`rvmsim.tune.lock`)."""
    return FolderLock(run_dir, "run", "run")


def is_run_folder(path: str | Path) -> bool:
    """Whether ``path`` holds a run (its ``run.sqlite``)."""
    return (Path(path) / RUN_DB).is_file()


def find_runs(runs_dir: str | Path) -> list[Path]:
    """The run folders directly inside ``runs_dir``, sorted."""
    runs_dir = Path(runs_dir)
    if not runs_dir.is_dir():
        return []
    return sorted(p for p in runs_dir.iterdir() if p.is_dir() and is_run_folder(p))


def open_run(run_dir: str | Path) -> RunStore:
    """The store of the run in ``run_dir``, opened read-only (a reader changes nothing in
    the folder, and never waits for its writer).

    Raises
    ------
    RvmsimError
        One line: no ``run.sqlite`` there, or not a readable one.
    """
    run_dir = Path(run_dir)
    if not is_run_folder(run_dir):
        raise RvmsimError(f"{run_dir}: no run database ({RUN_DB}) here")
    return RunStore(run_dir / RUN_DB, readonly=True)


def run_state(run_dir: str | Path, store: RunStore) -> RunState:
    """The state of the run in ``run_dir`` as it is now: the stored one, except that a run
    stored as running whose writer holds no lock any more (it was killed) is interrupted
    and resumable (``killed``).  Takes no lock."""
    state = store.state()
    if state.status is RunStatus.RUNNING and run_lock(run_dir).writer() is None:
        return dataclasses.replace(state, status=RunStatus.INTERRUPTED, killed=True)
    return state


def _legacy_config(doc: Any) -> Any:
    """A tuning config as rvmsim 0.1 dumped it: ``random.sigma0`` existed (and was
    ignored), so it is dropped."""
    if isinstance(doc, dict) and isinstance(doc.get("random"), dict):
        doc = {**doc, "random": {k: v for k, v in doc["random"].items() if k != "sigma0"}}
    return doc


def run_settings(run_dir: str | Path, store: RunStore) -> RunSettings:
    """The settings of the run in ``run_dir``: from its store, or, for a run of rvmsim 0.1,
    from its ``run.json``.

    Raises
    ------
    RvmsimError
        One line saying what to do: an old run without its ``run.json``, or an unreadable one.
    """
    settings = store.settings()
    if settings is not None:
        return settings
    run_json = Path(run_dir) / RUN_JSON
    if not run_json.is_file():
        raise RvmsimError(f"{run_dir}: a run of rvmsim 0.1 without its {RUN_JSON}: its settings "
                          "are not known (restore run.json, or start a new run)")
    try:
        doc = json.loads(run_json.read_text(encoding="utf-8"))
        return RunSettings.from_json({**doc, "config": _legacy_config(doc.get("config") or {})})
    except (ValueError, KeyError, TypeError, AttributeError) as err:
        msg = f"{run_json}: not a readable {RUN_JSON} ({err}); restore it, or start a new run"
        raise RvmsimError(" ".join(msg.split())) from None


def status_lines(run_dir: str | Path, top_m: int = 5) -> list[str]:
    """What ``rvmsim status`` prints: the state and the current top-M (while it runs, too);
    for a shared run also its scenes, and each top candidate's per-scene EC scores."""
    store = open_run(run_dir)
    try:
        state = run_state(run_dir, store)
        n = store.count()
        top = store.top(top_m)
        meta = store.meta()
        scenes, aggregate = meta.get("scenes"), meta.get("aggregate")
        members = {rec.idx: [m[0] for m in store.member_results(rec.idx)] for rec in top}
    finally:
        store.close()
    total = "" if state.total is None else f" / {state.total}"
    lines = [f"{run_dir}: {state.text}, strategy {state.strategy}, {n}{total} evaluations"]
    if isinstance(scenes, list) and scenes:
        names = ", ".join(str(r.get("vehicle") if isinstance(r, dict) else r) for r in scenes)
        lines.append(f"  shared by {len(scenes)} scenes ({names}); EC score: their {aggregate}")
    for k, rec in enumerate(top, start=1):
        fails = rec.failing()
        each = "" if not members[rec.idx] else "  [" + ", ".join(
            f"{m:.4g}" for m in members[rec.idx]) + "]"
        lines.append(f"  #{k}  EC score {rec.score:.4g}  trial {rec.idx:>6} ({rec.stage})  "
                     f"{'all pass' if not fails else 'fails ' + ','.join(fails)}{each}")
    return lines


def rank_text(rec: TrialRecord, rank: int, output: OutputSpec, vehicle: str | None = None) -> str:
    """A trial as a params file (YAML, loadable by :func:`rvmsim.isp.load_params`) with a
    comment line naming its rank, EC score, trial and stage."""
    import yaml

    of = "" if vehicle is None else f" of {vehicle}"
    return (f"# rank {rank}{of}: EC score {rec.score:.6g} (trial {rec.idx}, {rec.stage})\n"
            + yaml.safe_dump(params_to_dict(rec.params, output), sort_keys=False))


def rank_params_text(run_dir: str | Path, rank: int = 1) -> str:
    """The rank-K parameter set of a run as a params file (what ``rvmsim select`` writes),
    at the run's tuning output size.

    Raises
    ------
    RvmsimError
        One line: not a run, unreadable settings, or fewer than ``rank`` candidates.
    """
    store = open_run(run_dir)
    try:
        settings = run_settings(run_dir, store)
        top = store.top(rank)
    finally:
        store.close()
    if len(top) < rank:
        raise RvmsimError(f"{run_dir}: only {len(top)} candidates, no rank {rank}")
    return rank_text(top[rank - 1], rank, settings.config.output_spec())
