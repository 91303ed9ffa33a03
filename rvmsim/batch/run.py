"""Running a sweep: every design point not yet in ``sweep.sqlite`` as a task on an executor,
then the re-check rounds (:mod:`rvmsim.batch.recheck`) on the same executor.

Results (first-pass points and re-checks) stream into ``DIR/sweep.sqlite`` as they arrive,
so an interrupted sweep resumes where it stopped, in either phase, on either executor,
without re-running finished tasks.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Mapping
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from .._progress import progress_bar
from ..errors import RvmsimError
from .executors import Executor, LocalExecutor
from .payloads import MergedResult, PointResult, PointTask, YieldDoc, YieldError, YieldTask
from .point import run_point, run_yield
from .recheck import (grid_neighbours, merged_results, recheck_points, recheck_starts,
                      recheck_task, recheck_task_key)
from .spec import DesignPoint, SweepSpec, design_points, point_scene_doc
from .store import SWEEP_DB, SweepStore, sweep_lock

if TYPE_CHECKING:
    from .._progress import ProgressBar

__all__ = ["SweepResult", "point_task", "run_sweep", "stored_sweep", "PHASES", "phase_seconds"]

_Task = TypeVar("_Task")
_Result = TypeVar("_Result")


@dataclass(frozen=True)
class SweepResult:
    """A sweep's points and their final results (by point key, as
    :func:`~rvmsim.batch.recheck.merge_point` gives them, with a ``verdict``; a point not run
    yet has none); ``ran``: first-pass points computed in this session, ``rechecked``:
    re-checks computed in this session."""

    spec: SweepSpec
    points: list[DesignPoint]
    results: dict[str, MergedResult]
    ran: int
    out_dir: Path
    rechecked: int = 0

    def summary(self) -> str:
        """One line: the points, how many ran now, the re-checks run now, and the count of
        each verdict (and of points that failed to run)."""
        n_err = sum(1 for r in self.results.values() if "error" in r)
        kinds = [r.get("verdict") for r in self.results.values() if "error" not in r]
        n = len(self.points)
        return (f"sweep {self.spec.name}: {n} design points, {self.ran} run now, "
                f"{n - self.ran} already done, {self.rechecked} re-checks run now; "
                f"{kinds.count('pass')} pass every "
                f"{'market' if self.spec.markets else 'EC'}, {kinds.count('not found')} not found, "
                f"{kinds.count('infeasible')} infeasible"
                + (f", {n_err} failed to run (see sweep.csv)" if n_err else "")
                + "; seconds per phase over the points' final runs: "
                + ", ".join(f"{k} {v:.1f}" for k, v in phase_seconds(self.results).items()))


#: The timed phases of a point's run (its ``phases``), in order.
PHASES = ("render", "tune", "yield")


def phase_seconds(results: Mapping[str, MergedResult]) -> dict[str, float]:
    """Seconds per phase (:data:`PHASES`) summed over the points' final runs (each point's
    ``phases``; points stored before phases were timed count 0)."""
    out = dict.fromkeys(PHASES, 0.0)
    for r in results.values():
        phases = r.get("phases") if "error" not in r else None
        if isinstance(phases, Mapping):
            for k in PHASES:
                out[k] += float(phases.get(k, 0.0))
    return out


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
        meta = store.meta()
        store.sessions()
        store.done()
        store.rechecks()
    finally:
        store.close()
    _check_fingerprints(spec, meta, out_dir)


def _check_fingerprints(spec: SweepSpec, meta: dict[str, Any], out_dir: Path) -> None:
    """Refuse a stored sweep of other settings (``meta``: its settings as stored, JSON; a
    store from before re-checks or yields existed has no re-check or yield fingerprint, and
    resumes)."""
    rf, yf = meta.get("recheck_fingerprint"), meta.get("yield_fingerprint")
    if meta.get("fingerprint") != spec.fingerprint() or (
            rf is not None and rf != spec.recheck_fingerprint()) or (
            yf is not None and yf != spec.yield_fingerprint()):
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
    if meta:  # another sweep may have stored between check and lock
        try:
            _check_fingerprints(spec, meta, out_dir)
        except RvmsimError:
            store.close()
            raise
    session = store.sessions() + 1
    store.set_meta(fingerprint=spec.fingerprint(), name=spec.name, source=spec.source,
                   sessions=session, axes=[[n, list(v)] for n, v in spec.axes],
                   recheck_fingerprint=spec.recheck_fingerprint(),
                   yield_fingerprint=spec.yield_fingerprint())
    return store, session


def point_task(spec: SweepSpec, point: DesignPoint) -> PointTask:
    """The argument of :func:`~rvmsim.batch.point.run_point` for one design point."""
    doc, config = point_scene_doc(spec, point.values)
    task: PointTask = {
        "scene": doc, "config": config, "label": point.label, "strategy": spec.strategy,
        "budget": spec.budget, "seed": spec.seed, "criteria": spec.criteria_doc,
        "criteria_source": spec.criteria_source, "sensitivity": spec.sensitivity,
        "robustness": ({"samples": spec.robustness.samples, "seed": spec.robustness.seed}
                       if spec.robustness.samples else None)}
    if spec.markets:  # every market at once (rvmsim.batch.markets)
        task["markets"] = list(spec.markets)
    return task


def run_sweep(spec: SweepSpec, out_dir: str | Path, *, executor: Executor | None = None,
              force: bool = False, progress: bool = False,
              on_result: Callable[[DesignPoint, PointResult], None] | None = None
              ) -> SweepResult:
    """Run (or resume) a sweep into ``out_dir``: the first pass, then the re-check rounds.

    Finished points and re-checks in ``out_dir/sweep.sqlite`` are kept; the rest run on
    ``executor`` (default: this process), each stored as it arrives; first-pass results are
    then passed to ``on_result``.  A sweep whose settings changed (base scene, tuning,
    re-check settings, mesh files) refuses to resume unless ``force`` (which starts over,
    deleting the stored points only once this process holds the folder's lock).  An interruption (Ctrl-C) propagates; everything finished is in the
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
        executor = executor or LocalExecutor(1)
        try:
            points, ran, done = _run_points(spec, store, session, executor, progress,
                                            on_result)
            rechecks, rechecked = _run_rechecks(spec, store, session, executor, points, done,
                                                progress)
            _run_missing_yields(spec, store, executor, points, done, rechecks, progress)
        finally:
            store.close()
    return SweepResult(spec, points, merged_results(points, done, rechecks), ran, out_dir,
                       rechecked)


def _run_points(spec: SweepSpec, store: SweepStore, session: int, executor: Executor,
                progress: bool,
                on_result: Callable[[DesignPoint, PointResult], None] | None
                ) -> tuple[list[DesignPoint], int, dict[str, PointResult]]:
    """Run the points not in ``store`` yet, storing each as it arrives; (the sweep's
    points, how many ran now, every finished point by key)."""
    points = design_points(spec)
    done = store.done()
    todo = {p.task_key: p for p in points if p.key not in done}
    tasks = {key: point_task(spec, p) for key, p in todo.items()}
    ran = 0
    # closing: an exception in on_result stops the executor's tasks at once.
    with closing(_stream(executor, run_point, tasks, progress, len(points),
                         f"sweep {spec.name}", {k: p.label for k, p in todo.items()})
                 ) as arrivals:
        for task_key, result in arrivals:
            point = todo[task_key]
            store.add(point, result, session)
            done[point.key] = result
            ran += 1
            if on_result is not None:
                on_result(point, result)
    return points, ran, done


def _stream(executor: Executor, fn: Callable[[_Task], _Result], tasks: dict[str, _Task],
            progress: bool, total: int, desc: str, labels: Mapping[str, str]
            ) -> Generator[tuple[str, _Result], None, None]:
    """``fn`` (:func:`run_point`, :func:`run_yield`) over ``tasks`` on ``executor``,
    yielding (task key, result) as each arrives, with a progress bar (``total`` points,
    those not in ``tasks`` already done; the last point's label from ``labels``) when
    ``progress``."""
    bar: ProgressBar | None = None
    if progress and tasks:
        bar = progress_bar(total=total, initial=total - len(tasks), unit="point", desc=desc)
    try:
        for task_key, result in executor.run(fn, tasks):
            yield task_key, result
            if bar is not None:
                bar.update(1)
                if task_key in labels:
                    bar.set_postfix_str(labels[task_key])
    finally:
        if bar is not None:
            bar.close()


def _run_rechecks(spec: SweepSpec, store: SweepStore, session: int, executor: Executor,
                  points: list[DesignPoint], done: dict[str, PointResult], progress: bool
                  ) -> tuple[dict[tuple[str, int], PointResult], int]:
    """The re-check rounds (:mod:`rvmsim.batch.recheck`), each re-check not in ``store``
    yet run and stored as it arrives; (every finished re-check, how many ran now)."""
    rechecks = store.rechecks()
    neighbours = grid_neighbours(spec, points)
    merged = merged_results(points, done, rechecks, upto_round=0)
    turned: set[str] | None = None
    ran = 0
    for rnd in range(1, spec.recheck.rounds + 1):
        chosen = recheck_points(points, neighbours, merged, turned)
        if not chosen:
            break
        todo = {recheck_task_key(p, rnd): p for p in chosen if (p.key, rnd) not in rechecks}
        tasks = {k: recheck_task(point_task(spec, p), spec, rnd,
                                 recheck_starts(p, neighbours[p.key], merged,
                                                spec.recheck.neighbours), merged[p.key])
                 for k, p in todo.items()}
        with closing(_stream(executor, run_point, tasks, progress, len(chosen),
                             f"re-check {rnd}", {k: p.label for k, p in todo.items()})
                     ) as arrivals:
            for task_key, result in arrivals:
                point = todo[task_key]
                store.add_recheck(point, rnd, result, session)
                rechecks[(point.key, rnd)] = result
                ran += 1
        before, merged = merged, merged_results(points, done, rechecks, upto_round=rnd)
        turned = {k for k, r in merged.items() if _verdict(r) == "pass"
                  and _verdict(before[k]) != "pass"}
    return rechecks, ran


def _run_missing_yields(spec: SweepSpec, store: SweepStore, executor: Executor,
                        points: list[DesignPoint], done: dict[str, PointResult],
                        rechecks: dict[tuple[str, int], PointResult], progress: bool
                        ) -> None:
    """Measure the yield of each point whose best run has none although its scene has a
    variation section (a result stored before yields existed: every run since measures
    its own), adding it to that run's stored result (``done`` / ``rechecks`` too)."""
    if not (spec.has_variation and spec.robustness.samples):
        return  # no point's scene varies: nothing to look for (each look builds a scene)
    merged = merged_results(points, done, rechecks)
    todo: dict[str, tuple[DesignPoint, int]] = {}
    tasks: dict[str, YieldTask] = {}
    for p in points:
        r = merged.get(p.key)
        if r is None or "error" in r or "robustness" in r:
            continue
        task = point_task(spec, p)
        if task["scene"].get("variation") is not None:
            key = f"{p.task_key}-yield"
            todo[key] = (p, int(r["found_in"]))
            tasks[key] = {**task, "yield_of": r["params"]}
    with closing(_stream(executor, run_yield, tasks, progress, len(tasks), "yields",
                         {k: p.label for k, (p, _) in todo.items()})) as arrivals:
        for task_key, result in arrivals:
            point, rnd = todo[task_key]
            y: YieldDoc | YieldError
            if "error" in result:  # the point's scene failed to load on the worker
                y = {"error": f"yield: {result['error']}"}
            else:
                y = result["robustness"]
            store.set_yield(point, rnd, y)
            run = done[point.key] if rnd == 0 else rechecks[(point.key, rnd)]
            if "error" not in run:
                run["robustness"] = y


def _verdict(r: MergedResult) -> str | None:
    """A merged result's verdict; None for an error."""
    return None if "error" in r else r["verdict"]


def stored_sweep(spec: SweepSpec, out_dir: str | Path) -> SweepResult:
    """The points finished so far in ``out_dir/sweep.sqlite`` (after an interruption), with
    the re-checks finished so far, and ``ran`` 0; none before the store was made).  Reads
    only."""
    out_dir = Path(out_dir)
    done: dict[str, PointResult] = {}
    rechecks: dict[tuple[str, int], PointResult] = {}
    if (out_dir / SWEEP_DB).is_file():
        store = SweepStore(out_dir / SWEEP_DB, readonly=True)
        try:
            done = store.done()
            rechecks = store.rechecks()
        finally:
            store.close()
    points = design_points(spec)
    return SweepResult(spec, points, merged_results(points, done, rechecks), 0, out_dir)
