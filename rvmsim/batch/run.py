"""Running a sweep: every design point not yet in ``sweep.sqlite`` as a task on an executor.

Results stream into ``DIR/sweep.sqlite`` as they arrive, so an interrupted sweep resumes where
it stopped, on either executor, without re-running finished points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import RvmsimError
from .executors import Executor, LocalExecutor
from .point import run_point
from .spec import DesignPoint, SweepSpec, design_points, point_scene_doc
from .store import SWEEP_DB, SweepStore, sweep_lock

__all__ = ["SweepResult", "point_task", "run_sweep", "stored_sweep"]


@dataclass(frozen=True)
class SweepResult:
    """A sweep's points and the results there are (by point key; a point not run yet has
    none); ``ran``: points computed in this session."""

    spec: SweepSpec
    points: list[DesignPoint]
    results: dict[str, dict[str, Any]]
    ran: int
    out_dir: Path


def _check_out(spec: SweepSpec, out_dir: Path, force: bool) -> None:
    """Refuse, before anything is written: an output folder that is a file, one that
    another sweep is writing, or (without ``force``) a stored sweep that is not readable or
    whose settings differ."""
    if out_dir.exists() and not out_dir.is_dir():
        raise RvmsimError(f"{out_dir}: not a folder (a file is there); give --out a folder")
    sweep_lock(out_dir).check_free()
    db = out_dir / SWEEP_DB
    if force or not db.exists():
        return
    store = SweepStore(db, readonly=True)
    try:
        fingerprint = store.meta().get("fingerprint")
        store.sessions()
        store.done()
    finally:
        store.close()
    if fingerprint != spec.fingerprint():
        raise RvmsimError(f"{out_dir}: this sweep's settings or base scene changed since it "
                          "started (results would mix); use --force to start over")


def _open_store(spec: SweepSpec, out_dir: Path, force: bool) -> tuple[SweepStore, int]:
    """The sweep's store (emptied first with ``force``) and this session's number, once
    this process holds the folder's lock (:func:`_check_out` has checked the rest)."""
    db = out_dir / SWEEP_DB
    if force and db.exists():
        for suffix in ("", "-wal", "-shm"):
            Path(str(db) + suffix).unlink(missing_ok=True)
    store = SweepStore(db)
    meta = store.meta()
    fp = spec.fingerprint()
    if meta and meta.get("fingerprint") != fp:  # another sweep stored between check and lock
        store.close()
        raise RvmsimError(f"{out_dir}: this sweep's settings or base scene changed since it "
                          "started (results would mix); use --force to start over")
    session = store.sessions() + 1
    store.set_meta(fingerprint=fp, name=spec.name, source=spec.source, sessions=session,
                   axes=[[n, list(v)] for n, v in spec.axes])
    return store, session


def point_task(spec: SweepSpec, point: DesignPoint) -> dict[str, Any]:
    """The argument of :func:`~rvmsim.batch.point.run_point` for one design point."""
    doc, config = point_scene_doc(spec, point.values)
    return {"scene": doc, "config": config, "label": point.label, "strategy": spec.strategy,
            "budget": spec.budget, "seed": spec.seed, "criteria": spec.criteria_doc,
            "criteria_source": spec.criteria_source, "sensitivity": spec.sensitivity}


def run_sweep(spec: SweepSpec, out_dir: str | Path, *, executor: Executor | None = None,
              force: bool = False, progress: bool = False,
              on_result: Callable[[DesignPoint, dict[str, Any]], None] | None = None
              ) -> SweepResult:
    """Run (or resume) a sweep into ``out_dir``.

    Finished points in ``out_dir/sweep.sqlite`` are kept; the rest run on ``executor``
    (default: this process), each stored as it arrives, then passed to ``on_result``.  A
    sweep whose settings changed (base scene, tuning, mesh files) refuses to resume unless
    ``force`` (which starts over, deleting the stored points only once this process holds
    the folder's lock).  An interruption (Ctrl-C) propagates; everything finished is in the
    store (:func:`stored_sweep` reads it).

    Raises
    ------
    RvmsimError
        One line, before anything is written: ``out_dir`` is a file, another sweep is
        writing it (``DIR is in use by process N``), or its store is unreadable or of
        another sweep.
    """
    out_dir = Path(out_dir)
    _check_out(spec, out_dir, force)
    with sweep_lock(out_dir):
        store, session = _open_store(spec, out_dir, force)
        try:
            points, ran, done = _run_points(spec, store, session,
                                            executor or LocalExecutor(1), progress, on_result)
        finally:
            store.close()
    return SweepResult(spec, points, done, ran, out_dir)


def _run_points(spec: SweepSpec, store: SweepStore, session: int, executor: Executor,
                progress: bool,
                on_result: Callable[[DesignPoint, dict[str, Any]], None] | None
                ) -> tuple[list[DesignPoint], int, dict[str, dict[str, Any]]]:
    """Run the points not in ``store`` yet, storing each as it arrives; (the sweep's
    points, how many ran now, every finished point by key)."""
    points = design_points(spec)
    done = store.done()
    todo = {p.task_key: p for p in points if p.key not in done}
    tasks = {key: point_task(spec, p) for key, p in todo.items()}
    bar = None
    if progress and tasks:
        from tqdm import tqdm

        bar = tqdm(total=len(points), initial=len(points) - len(tasks), unit="point",
                   desc=f"sweep {spec.name}")
    ran = 0
    try:
        for task_key, result in executor.run(run_point, tasks):
            point = todo[task_key]
            store.add(point, result, session)
            done[point.key] = result
            ran += 1
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(point.label)
            if on_result is not None:
                on_result(point, result)
    finally:
        if bar is not None:
            bar.close()
    return points, ran, done


def stored_sweep(spec: SweepSpec, out_dir: str | Path) -> SweepResult:
    """The points finished so far in ``out_dir/sweep.sqlite`` (after an interruption), with
    ``ran`` 0; none before the store was made).  Reads only."""
    out_dir = Path(out_dir)
    done: dict[str, dict[str, Any]] = {}
    if (out_dir / SWEEP_DB).is_file():
        store = SweepStore(out_dir / SWEEP_DB, readonly=True)
        try:
            done = store.done()
        finally:
            store.close()
    return SweepResult(spec, design_points(spec), done, 0, out_dir)
