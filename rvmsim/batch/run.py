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
from .store import SweepStore

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


def _open_store(spec: SweepSpec, out_dir: Path, force: bool) -> tuple[SweepStore, int]:
    """The sweep's store (emptied first with ``force``) and this session's number; refuses a
    store whose sweep settings differ."""
    db = out_dir / "sweep.sqlite"
    if force and db.exists():
        for suffix in ("", "-wal", "-shm"):
            Path(str(db) + suffix).unlink(missing_ok=True)
    store = SweepStore(db)
    meta = store.meta()
    fp = spec.fingerprint()
    if meta and meta.get("fingerprint") != fp:
        store.close()
        raise RvmsimError(f"{out_dir}: this sweep's settings or base scene changed since it "
                          "started (results would mix); use --force to start over")
    session = int(meta.get("sessions", 0)) + 1
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
    ``force`` (which starts over).  An interruption (Ctrl-C) propagates; everything finished
    is in the store (:func:`stored_sweep` reads it).
    """
    out_dir = Path(out_dir)
    store, session = _open_store(spec, out_dir, force)
    points = design_points(spec)
    done = store.done()
    todo = {p.task_key: p for p in points if p.key not in done}
    tasks = {key: point_task(spec, p) for key, p in todo.items()}
    bar = None
    if progress and tasks:
        from tqdm import tqdm

        bar = tqdm(total=len(points), initial=len(points) - len(tasks), unit="point",
                   desc=f"sweep {spec.name}")
    executor = executor or LocalExecutor(1)
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
        store.close()
    return SweepResult(spec, points, done, ran, out_dir)


def stored_sweep(spec: SweepSpec, out_dir: str | Path) -> SweepResult:
    """The points finished so far in ``out_dir/sweep.sqlite`` (after an interruption), with
    ``ran`` 0."""
    out_dir = Path(out_dir)
    store = SweepStore(out_dir / "sweep.sqlite")
    try:
        done = store.done()
    finally:
        store.close()
    return SweepResult(spec, design_points(spec), done, 0, out_dir)
