"""Tune one vehicle: render once (cached), search, store every candidate, write the results.

A run lives in a folder: ``run.sqlite`` (settings, state and every candidate, see
:mod:`rvmsim.runs.store`), ``run.json`` (the settings, for people), and at the end
``top/`` (the diverse top-M, :mod:`rvmsim.runs.diverse`: ``rank_K.yaml`` params files and
``candidates.json``) and ``best/`` (the best candidate's RVM
image, annotated EC image and EC table).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from .._progress import progress_bar
from ..errors import RvmsimError
from ..runs.folder import RUN_DB, RUN_JSON, open_run, run_json_disagreement, run_lock, run_settings
from ..runs.records import RunSettings, RunStatus
from ..runs.store import RunStore
from ..scene import Scene
from ..scene.display import RVM_IMAGE_OF_RECORD_PX
from ..search.config import make_strategy
from ..search.strategies import Strategy, check_seed
from .kinds import Built, MemberSet, Verdict, member_set
from .loop import SearchOutcome
from .new_run import new_run_settings
from .requests import RunOptions, SearchOptions, TuneRequest
from .resumed import ResumeArgs, check_resume_args
from .results import remove_run

if TYPE_CHECKING:
    from .._progress import ProgressBar
    from ..criteria import Criteria
    from ..storage import FolderLock

__all__ = ["tune", "resume", "TuneResult", "DISPLAY_SIZE"]

#: The default RVM image of record (:data:`rvmsim.scene.RVM_IMAGE_OF_RECORD_PX`), under its
#: old name; a scene's or criteria file's ``display.rvm_image_px`` sets a car's own.
DISPLAY_SIZE = RVM_IMAGE_OF_RECORD_PX


@dataclass(frozen=True)
class TuneResult:
    """A finished (or stopped) tuning run: its folder, what the search did, the evaluations
    the strategy planned (None: unknown in advance), the verdict on its best setting
    (:class:`rvmsim.tune.kinds.Verdict`: ``verdict.exit_status`` is ``rvmsim tune``'s) and
    its scene file as recorded (the first, for a shared run; None: not known)."""

    run_dir: Path
    outcome: SearchOutcome
    total: int | None
    verdict: Verdict
    scene: str | None = None


def _check_out(run_dir: Path) -> None:
    """Refuse a run folder that is a file."""
    if run_dir.exists() and not run_dir.is_dir():
        raise RvmsimError(f"{run_dir}: not a folder (a file is there); give a run folder")


def _new_run(run_dir: Path, request: TuneRequest, force: bool
             ) -> tuple[RunSettings, list[Scene], Criteria]:
    """The settings, scenes and criteria of a new run in ``run_dir`` (nothing written yet:
    every input is checked, before anything in ``run_dir`` changes, by
    :func:`rvmsim.tune.new_run.new_run_settings`)."""

    if not force and (run_dir / RUN_DB).exists():
        raise RvmsimError(f"{run_dir}: a run exists here already; use --resume to continue it, "
                          "or --force to replace it")
    return new_run_settings(request)


def _resumed_run(run_dir: Path, given: ResumeArgs | None
                 ) -> tuple[RunSettings, list[Scene], Criteria]:
    """The settings, scene and criteria of the run to resume in ``run_dir`` (read, not
    written), checking what the caller ``given`` against them (:mod:`.resumed`), its
    run.json against its store, and that its scene has not changed since."""

    if not (run_dir / RUN_DB).is_file():
        raise RvmsimError(f"{run_dir}: no run to resume ({RUN_DB} missing)")
    store = open_run(run_dir)
    try:
        stored = store.settings()  # None: a run of rvmsim 0.1, whose run.json is its truth
        settings = run_settings(run_dir, store)
        # a status or a trial this version cannot read is refused before anything changes
        store.state()
        store.replay()
    finally:
        store.close()
    check_seed(settings.seed, f"{run_dir / RUN_DB}: seed")
    if given is not None:
        check_resume_args(run_dir, settings, given)
    differs = None if stored is None else run_json_disagreement(run_dir, settings)
    if differs:
        raise RvmsimError(f"{differs}: the settings live in {RUN_DB} and {RUN_JSON} only "
                          f"exports them; restore {RUN_JSON}, or delete it to resume with the "
                          "stored settings (it is written anew)")
    kind = member_set(settings)
    scenes = kind.resumed_scenes(run_dir / RUN_DB)
    return settings, scenes, kind.resumed_criteria()


def _writable_store(run_dir: Path, settings: RunSettings, resume: bool, force: bool) -> RunStore:
    """The run's store, opened for writing once this process holds the run's lock: a
    resumed run's (still the run that was read), or a new one (replacing the old run only
    with ``force``, and only now that everything it needs has loaded)."""
    db = run_dir / RUN_DB
    if resume:
        store = RunStore(db)
        stored = store.settings()
        if stored is not None and stored != settings:
            store.close()
            raise RvmsimError(f"{db}: the run was replaced while this resume started; "
                              "resume it again")
    else:
        if force:
            remove_run(run_dir)
        elif db.exists():  # made by a writer that finished between our check and our lock
            raise RvmsimError(f"{run_dir}: a run exists here already; use --resume to "
                              "continue it, or --force to replace it")
        store = RunStore(db)
    # run.json exports the settings (a resumed run's too: the store is the truth)
    (run_dir / RUN_JSON).write_text(json.dumps(settings.as_json(), indent=2))
    return store


def _progress_bar(on: bool, total: int | None, vehicle: str,
                  position: int) -> tuple[ProgressBar | None, Callable[[int, float, str], None]]:
    """A tqdm bar (or None when ``on`` is false) and the search's ``on_batch`` updating it."""
    bar = None
    if on:
        bar = progress_bar(total=total, unit="eval", desc=f"tune {vehicle}", smoothing=0.1,
                   position=position, leave=position == 0)

    def on_batch(done: int, best: float, stage: str) -> None:
        if bar is not None:
            if bar.total is not None and done > bar.total:  # a last batch past the budget
                bar.total = done
            bar.set_postfix_str(f"best {best:.4g} [{stage}]", refresh=False)
            bar.update(done - bar.n)

    return bar, on_batch


def tune(request: TuneRequest, run_dir: str | Path, *, options: RunOptions = RunOptions(),
         force: bool = False) -> TuneResult:
    """Tune the ISP for one scene, or one parameter set for several (shared tuning, see
    :mod:`rvmsim.tune.shared`); see the module docstring for what is written.

    Parameters
    ----------
    request : TuneRequest
        What defines the run: scenes, strategy, config, criteria, seed, budget, robust or
        shared settings.
    run_dir : path
        The run folder.
    options : RunOptions
        Worker processes, time limits, progress bar.
    force : bool
        Replace a run in ``run_dir`` (``--force``).  The old run is deleted only once every
        input of the new one has loaded, the scene has rendered and this process holds the
        run's lock; an error before that leaves it as it was.

    Raises
    ------
    RvmsimError
        One line: a bad input (scene, criteria, config, strategy, seed, budget), a run
        folder that is a file or holds a run already (without ``force``), or one in use
        by another writer (``RUN is in use by process N``).
    """
    run_dir = Path(run_dir)
    _check_out(run_dir)
    lock = run_lock(run_dir)
    lock.check_free()  # another writer: say so at once (its lock, taken below, decides)
    settings, scenes, crit = _new_run(run_dir, request, force)
    return _run(run_dir, lock, settings, scenes, crit, options, resume=False, force=force)


def resume(run_dir: str | Path, *, options: RunOptions = RunOptions(),
           given: ResumeArgs | None = None) -> TuneResult:
    """Continue the run in ``run_dir`` with its own settings, read from its store (after
    Ctrl-C, a kill, ``--max-time``): the same final result as an unbroken run.

    ``given``: what the caller gave besides the run (``tune SCENE --resume RUN --budget
    …``), each of which must be the run's own (:mod:`rvmsim.tune.resumed`).

    Raises
    ------
    RvmsimError
        One line: no run there, an unreadable store, something ``given`` that the run was
        not made with, a run.json that disagrees with the store, a scene or variation
        changed since the run started, or a run in use by another writer.
    """
    run_dir = Path(run_dir)
    _check_out(run_dir)
    lock = run_lock(run_dir)
    lock.check_free()
    settings, scenes, crit = _resumed_run(run_dir, given)
    return _run(run_dir, lock, settings, scenes, crit, options, resume=True, force=False)


def _run(run_dir: Path, lock: FolderLock, settings: RunSettings, scenes: list[Scene],
         crit: Criteria, options: RunOptions, *, resume: bool, force: bool) -> TuneResult:
    """Render, search into the run's store under its lock, write the results: one path for
    every run kind (:func:`rvmsim.tune.kinds.member_set`)."""

    sc, cfg = scenes[0], settings.config
    # the strategy before the render: a bad config, strategy or seed fails in a moment
    strat = make_strategy(settings.strategy, cfg.space(sc.fisheye_camera()), cfg,
                          settings.seed, settings.budget)
    kind = member_set(settings)
    built = kind.build(scenes, progress=options.progress)
    with lock:
        store = _writable_store(run_dir, settings, resume, force)
        try:
            outcome = _search(store, kind, built, settings, strat, crit, options,
                              _progress_bar(options.progress, strat.total(), sc.name,
                                            options.progress_position))
            verdict = kind.write_results(run_dir, store, scenes, built, crit)
        finally:
            store.close()
    return TuneResult(run_dir, outcome, strat.total(), verdict, settings.scene)


def _search(store: RunStore, kind: MemberSet, built: Built, settings: RunSettings,
            strat: Strategy, crit: Criteria, options: RunOptions,
            bar: tuple[ProgressBar | None, Callable[[int, float, str], None]]) -> SearchOutcome:
    """Search into ``store``, recording the run's state: running, then done, interrupted
    (Ctrl-C) or failed (an error, passed on as it is)."""
    store.begin(settings, strat.space, strat.total())
    progress, on_batch = bar
    try:
        outcome = kind.search(built, kind.search_settings(settings.config, crit, strat), store,
                              SearchOptions(options.workers, options.max_time,
                                            options.target_score, on_batch))
    except KeyboardInterrupt:
        store.set_state(RunStatus.INTERRUPTED)
        raise
    except Exception:  # recorded, then passed on as it is
        store.set_state(RunStatus.FAILED)
        raise
    finally:
        if progress is not None:
            progress.close()
    store.set_state(RunStatus.DONE, outcome.stopped)
    return outcome
