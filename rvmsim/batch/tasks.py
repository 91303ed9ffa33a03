"""``rvmsim batch``: one tuning run per scene, and the summary table over them.

Locally the scenes are tuned one after another, each on ``workers`` processes
(:func:`rvmsim.tune.tune`).  With a Dask scheduler each scene is one task on the cluster
(:func:`tune_task`); its run folder comes back as bytes and is written into
``out/<scene name>/``; the run records this machine's scene and criteria paths, so ``status``, ``select``, ``report`` and ``--resume`` work on it as on a local
run.  A scene that cannot be loaded or tuned is reported as a failed :class:`SceneRun`; the
others still run.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..criteria import bundled_criteria_text, criteria_from_text, criteria_reference, load_criteria
from ..errors import RvmsimError
from ..scene import absolute_mesh_paths, read_scene_document, scene_from_dict
from ..tune import RunOptions, TuneRequest, tune
from ..search import TuningConfig
from .executors import DaskExecutor, task_malloc
from .payloads import BatchError, BatchRun, BatchTask, SceneSummary, SceneSummaryError


__all__ = ["BatchSettings", "SceneRun", "run_batch", "summary_ec_ids", "summary_table",
           "write_summary", "tune_task", "portable_scene_doc"]


@dataclass(frozen=True)
class BatchSettings:
    """How every scene of a batch is tuned (as ``rvmsim tune``'s options).

    ``workers``: local processes per scene (a Dask task uses one).
    """

    strategy: str
    config: TuningConfig
    criteria_file: Path | None = None
    seed: int = 0
    budget: int | None = None
    workers: int = 1


@dataclass(frozen=True)
class SceneRun:
    """One scene's outcome: its run folder and best candidate, or the error that skipped it.

    ``ecs`` maps EC id → passed, in the criteria's order; ``seconds`` is the tuning wall time
    rounded to 0.1 s.
    """

    scene: Path
    run_dir: Path | None = None
    error: str | None = None
    vehicle: str = ""
    ec_score: float = 0.0
    passed: bool = False
    ecs: Mapping[str, bool] = field(default_factory=dict)
    evaluations: int = 0
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return self.error is None

    @classmethod
    def failed(cls, scene: Path, err: BaseException | str) -> SceneRun:
        return cls(scene, error=str(err))

    @classmethod
    def finished(cls, scene: Path, run_dir: Path, evaluations: int, seconds: float) -> SceneRun:
        """The run in ``run_dir``, read from its ``best/ec.json``."""
        doc = json.loads((run_dir / "best" / "ec.json").read_text())
        return cls(scene, run_dir, vehicle=doc["vehicle"], ec_score=doc["ec_score"],
                   passed=doc["passed"], ecs={e["id"]: e["passed"] for e in doc["ecs"]},
                   evaluations=evaluations, seconds=round(seconds, 1))

    def summary_row(self) -> SceneSummary | SceneSummaryError:
        """This scene's entry of ``summary.json``."""
        if self.error is not None:
            return {"scene": str(self.scene), "error": self.error}
        return {"scene": str(self.scene), "vehicle": self.vehicle, "ec_score": self.ec_score,
                "passed": self.passed, "ecs": dict(self.ecs), "evaluations": self.evaluations,
                "seconds": self.seconds, "run": str(self.run_dir)}


def run_batch(scenes: Sequence[Path], out: Path, settings: BatchSettings, *,
              scheduler: str | None = None, progress: bool = False,
              on_start: Callable[[int, Path], None] | None = None) -> Iterator[SceneRun]:
    """Tune every scene into ``out/<scene name>/``, yielding each :class:`SceneRun` as it
    finishes (in order locally, in completion order on a cluster).

    Parameters
    ----------
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a Dask cluster: one task per scene there.
    progress : bool
        Each local scene's tuning bar (on the second line, under the caller's own).
    on_start : callable, optional
        ``on_start(k, scene)`` before local scene ``k`` (1-based) starts.

    Raises
    ------
    RvmsimError
        The cluster cannot be reached or a task failed there (not a bad scene: that is a
        failed SceneRun).
    OSError
        A run folder cannot be written.
    """
    if scheduler:
        return _remote_runs(scenes, out, settings, scheduler)
    return _local_runs(scenes, out, settings, progress, on_start)


def _local_runs(scenes: Sequence[Path], out: Path, settings: BatchSettings, progress: bool,
                on_start: Callable[[int, Path], None] | None) -> Iterator[SceneRun]:

    for k, scene in enumerate(scenes, start=1):
        if on_start is not None:
            on_start(k, scene)
        run_dir = out / scene.stem
        try:
            r = tune(TuneRequest((scene,), settings.strategy, settings.config,
                                 criteria_file=settings.criteria_file, seed=settings.seed,
                                 budget=settings.budget), run_dir,
                     options=RunOptions(settings.workers, progress=progress,
                                        progress_position=1))
        except RvmsimError as err:
            yield SceneRun.failed(scene, err)
            continue
        yield SceneRun.finished(scene, run_dir, r.outcome.evaluated + r.outcome.replayed,
                                r.outcome.seconds)


def _remote_runs(scenes: Sequence[Path], out: Path, settings: BatchSettings,
                 scheduler: str) -> Iterator[SceneRun]:

    tasks: dict[str, BatchTask] = {}
    by_key: dict[str, Path] = {}
    for k, scene in enumerate(scenes):
        try:  # a bad scene or criteria file skips the scene, as in local runs
            doc = portable_scene_doc(scene)
            crit = None if not settings.criteria_file else (  # a bundled set's name, or a file
                bundled_criteria_text(settings.criteria_file)
                or Path(settings.criteria_file).read_text())
        except (RvmsimError, OSError) as err:
            yield SceneRun.failed(scene, err)
            continue
        key = f"batch-{k}-{scene.stem}"
        by_key[key] = scene
        tasks[key] = {"scene": doc, "config": settings.config.model_dump(mode="json"),
                      "strategy": settings.strategy, "seed": settings.seed,
                      "budget": settings.budget, "criteria": crit, "workers": 1,
                      "scene_file": str(scene.resolve()),
                      "criteria_file": (None if settings.criteria_file is None
                                        else criteria_reference(settings.criteria_file))}
    with DaskExecutor(scheduler) as ex:
        for key, res in ex.run(tune_task, tasks):
            scene = by_key[key]
            if "error" in res:
                yield SceneRun.failed(scene, res["error"])
                continue
            run_dir = out / scene.stem
            _write_run_folder(run_dir, res["files"])
            yield SceneRun.finished(scene, run_dir, res["evaluated"] + res["replayed"],
                                    res["seconds"])


def _write_run_folder(run_dir: Path, files: Mapping[str, bytes]) -> None:
    """Write a run made on a worker into ``run_dir`` (it already records this machine's
    scene and criteria paths: :func:`tune_task`'s ``scene_file`` and ``criteria_file``)."""
    for rel, data in files.items():
        (run_dir / rel).parent.mkdir(parents=True, exist_ok=True)
        (run_dir / rel).write_bytes(data)


def summary_ec_ids(runs: Sequence[SceneRun], criteria_file: Path | None) -> tuple[str, ...]:
    """The summary table's EC columns: the ECs the finished runs were judged by (one
    criteria file for all), else those of the criteria file."""
    for r in runs:
        if r.ok:
            return tuple(r.ecs)

    try:
        return load_criteria(criteria_file).ids
    except RvmsimError:  # already reported as every scene's error: no EC columns then
        return ()


def summary_table(runs: Sequence[SceneRun], ec_ids: Sequence[str]) -> str:
    """The batch summary as text: per scene the vehicle, EC score, ok/X per EC in
    ``ec_ids``, evaluations and seconds, or its error."""
    head = f"{'vehicle':28} {'EC score':>10} " + " ".join(f"{e:>3}" for e in ec_ids)
    lines = [head + f" {'evals':>7} {'time':>7}"]
    for r in runs:
        if r.error is not None:
            lines.append(f"{str(r.scene):28} {'error':>10}  {r.error}")
            continue
        marks = " ".join(f"{'ok' if r.ecs[e] else 'X':>3}" for e in ec_ids)
        lines.append(f"{r.vehicle[:28]:28} {r.ec_score:10.4g} {marks} "
                     f"{r.evaluations:7d} {r.seconds:6.1f}s")
    return "\n".join(lines)


def write_summary(out: Path, runs: Sequence[SceneRun], table: str) -> list[Path]:
    """Write ``out/summary.json`` (one entry per scene) and ``out/summary.txt`` (``table``).

    Raises
    ------
    RvmsimError
        ``out`` cannot be written (one line).
    """
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / "summary.json").write_text(json.dumps([r.summary_row() for r in runs], indent=2))
        (out / "summary.txt").write_text(table + "\n")
    except OSError as err:
        raise RvmsimError(f"{out}: {err.strerror or err}") from None
    return [out / "summary.json", out / "summary.txt"]


# ---------------------------------------------------------------------------- cluster tasks
def portable_scene_doc(scene_file: str | Path) -> dict[str, Any]:
    """The scene file's document (YAML) with its mesh paths made absolute, so it loads from
    any folder (a task on a cluster worker builds its scene from it)."""

    _, doc = read_scene_document(scene_file)  # one-line errors here, not on a worker
    absolute_mesh_paths(doc, Path(scene_file).parent)
    return doc


def tune_task(task: BatchTask) -> BatchRun | BatchError:
    """One vehicle's tuning run (:func:`rvmsim.tune.tune`) as a task for a cluster worker.

    ``task``: ``scene`` (a :func:`portable_scene_doc`), ``config`` (a tuning config
    document), ``strategy``, ``seed``, ``budget``, optionally ``criteria`` (a criteria
    file's text), ``workers``, and ``scene_file`` / ``criteria_file``: the paths to record
    in the run (the files on the submitting machine).  The run is made in a temporary folder
    and returned as ``{"files": {relative path: bytes}, "evaluated", "replayed",
    "seconds"}`` (or ``{"error": message}``), for the caller to write into its run folder.
    """

    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

    try:
        with tempfile.TemporaryDirectory(prefix="rvmsim-tune-") as tmp, task_malloc():
            recorded = task.get("scene_file") or "scene.yaml"
            scene = scene_from_dict(task["scene"], source=str(recorded))
            crit_source = task.get("criteria_file") or "criteria"  # resolves plugin paths
            text = task.get("criteria")
            criteria = criteria_from_text(text, crit_source) if text else None
            run_dir = Path(tmp) / "run"
            request = TuneRequest((scene,), task["strategy"],
                                  TuningConfig.model_validate(task["config"]), criteria,
                                  task.get("criteria_file"), task["seed"], task.get("budget"),
                                  scene_file=recorded)
            res = tune(request, run_dir, options=RunOptions(task.get("workers", 1)))
            files = {str(p.relative_to(run_dir)): p.read_bytes()
                     for p in sorted(run_dir.rglob("*")) if p.is_file()}
            return {"files": files, "evaluated": res.outcome.evaluated,
                    "replayed": res.outcome.replayed, "seconds": res.outcome.seconds}
    except RvmsimError as err:
        return {"error": str(err)}
