"""What ``rvmsim tune --resume RUN`` may be given besides the run, checked against the run's
stored settings before anything is read further or written.

A resumed run keeps its own settings (``run.sqlite``; :class:`~rvmsim.runs.RunSettings`):
that is what makes its final result that of an unbroken run.  So every option that defines
a run, given with ``--resume``, must say what the run already is, or the resume is refused
(one line naming the option, the run's store and what it was made with; nothing changes):

- SCENE (and SCENE1 SCENE2 … of a shared run, in order): each the run's own scene, by its
  resolved path or by content (:func:`rvmsim.render.same_scene` on the stored fingerprint);
- ``--shared``, ``--markets``, ``--robust``, ``--samples``, ``--variation``,
  ``--compensation``, ``--aggregate``, ``--strategy``, ``--seed``, ``--budget``, ``--config``
  (the file's settings at the run's image of record), ``--criteria``,
  ``--only-supported``: the stored values;
- ``--out``: the run's own folder; ``--force`` (replace a run) is never one with ``--resume``.

Options that only say how the run goes here (``--workers``, ``--max-time``,
``--target-score``, ``--progress``) are the caller's to choose.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from ..errors import RvmsimError
from ..runs.folder import RUN_DB, json_difference
from ..runs.records import RobustRecord, RunSettings, SceneRef
from ..render import same_scene
from ..scene import load_scene
from ..compensation import compensation_for, compensation_from_dict
from ..markets import parse_markets
from .members import parse_aggregate
from .robust import ROBUST_AGGREGATE
from ..criteria import criteria_reference
from ..search.config import load_tuning_config

__all__ = ["ResumeArgs", "check_resume_args"]


@dataclass(frozen=True)
class ResumeArgs:
    """What a ``tune --resume`` call gave besides the run folder (None, False or empty: the
    option was not given), each checked by :func:`check_resume_args`."""

    scenes: tuple[Path, ...] = ()
    shared: bool = False
    markets: str | None = None
    robust: bool = False
    samples: int | None = None
    variation_file: Path | None = None
    compensation: str | None = None
    aggregate: str | None = None
    strategy: str | None = None
    seed: int | None = None
    budget: int | None = None
    config_file: Path | None = None
    criteria_file: Path | None = None
    out: Path | None = None
    force: bool = False
    only_supported: bool = False


def _refuse(option: str, db: Path, made: str, given: str | None = None) -> RvmsimError:
    """The one line refusing ``option`` (shown as given: ``given``)."""
    shown = option if given is None else f"{option} {given}"
    return RvmsimError(f"{shown}: {db} was made {made}; --resume continues a run with its own "
                       f"settings (give no {option}, or start a new run with --out)")


def _stored_scenes(settings: RunSettings) -> tuple[SceneRef, ...]:
    return settings.scenes or (SceneRef(settings.scene, settings.scene_key, settings.vehicle),)


def _same_file(given: Path, recorded: str) -> bool:
    try:
        return given.resolve() == Path(recorded).resolve()
    except OSError:
        return False


def _check_scenes(db: Path, settings: RunSettings, scenes: tuple[Path, ...]) -> None:
    stored = _stored_scenes(settings)
    if len(scenes) != len(stored):
        names = ", ".join(r.scene for r in stored)
        raise RvmsimError(f"tune: {len(scenes)} scenes given with --resume, but {db} was made "
                          f"for {len(stored)} ({names}); --resume continues a run on its own "
                          "scenes (give no SCENE, or start a new run with --out)")
    for given, ref in zip(scenes, stored):
        if _same_file(given, ref.scene):
            continue
        if ref.scene_key is not None and same_scene(ref.scene_key, load_scene(given), given):
            continue
        raise RvmsimError(f"{given}: the run in {db.parent} was made for another scene "
                          f"({ref.scene}); --resume continues a run on its own scene (give "
                          "no SCENE, or start a new run with --out)")


def _kind(settings: RunSettings) -> str:
    """What kind of run ``settings`` are, for a refusal."""
    if settings.kind.markets:
        return f"for the markets {','.join(settings.kind.markets)}"
    if settings.shared:
        return f"for {len(settings.scenes)} scenes (--shared)"
    return "for one scene"


def _check_members(db: Path, settings: RunSettings, a: ResumeArgs) -> None:
    """--shared, --markets, --robust, --samples, --variation, --compensation, --aggregate."""

    kind = settings.kind
    if a.shared and not (settings.shared and not kind.markets):
        raise _refuse("--shared", db, _kind(settings))
    if a.markets is not None and tuple(m.spec for m in parse_markets(a.markets)) \
            != tuple(kind.markets):
        raise _refuse("--markets", db, _kind(settings), a.markets)
    robust = kind.robust
    if (a.robust or a.samples is not None or a.variation_file is not None
            or a.compensation is not None) and robust is None:
        raise _refuse("--robust", db, "without --robust")
    if robust is not None:
        _check_robust(db, robust, a)
    if a.aggregate is not None:
        if not (settings.shared or settings.robust):
            raise _refuse("--aggregate", db, "for one scene without --robust (no members to "
                          "aggregate)", a.aggregate)
        stored = kind.aggregate or (ROBUST_AGGREGATE if settings.robust else "min")
        if parse_aggregate(a.aggregate).text != parse_aggregate(stored).text:
            raise _refuse("--aggregate", db, f"with --aggregate '{stored}'", f"'{a.aggregate}'")


def _check_robust(db: Path, robust: RobustRecord, a: ResumeArgs) -> None:
    """--samples, --variation, --compensation against a robust run's."""
    if a.samples is not None and a.samples != robust.samples:
        raise _refuse("--samples", db, f"with --samples {robust.samples}", str(a.samples))
    if a.variation_file is not None and str(a.variation_file.resolve()) != robust.variation_file:
        raise _refuse("--variation", db, "with " + (
            f"--variation {robust.variation_file}" if robust.variation_file
            else "each scene's own variation section"), str(a.variation_file))
    if a.compensation is not None:
        model = compensation_for(a.compensation)
        recorded = (compensation_from_dict(robust.compensation).as_dict()
                    if robust.compensation else None)
        if model is None or model.as_dict() != recorded:
            raise _refuse("--compensation", db, "with another compensation model"
                          if robust.compensation else "without --compensation",
                          a.compensation)


def _check_search(db: Path, settings: RunSettings, a: ResumeArgs) -> None:
    """--strategy, --seed, --budget, --config, --criteria."""

    if a.strategy is not None and a.strategy != settings.strategy:
        raise _refuse("--strategy", db, f"with --strategy {settings.strategy}", a.strategy)
    if a.seed is not None and a.seed != settings.seed:
        raise _refuse("--seed", db, f"with --seed {settings.seed}", str(a.seed))
    if a.budget is not None and a.budget != settings.budget:
        raise _refuse("--budget", db, "without --budget (the config's)" if settings.budget is None
                      else f"with --budget {settings.budget}", str(a.budget))
    if a.config_file is not None:
        mine = load_tuning_config(a.config_file).at_record(settings.record_px)
        key = json_difference(mine.model_dump(mode="json"),
                                settings.config.model_dump(mode="json"))
        if key:
            raise _refuse("--config", db, f"with other tuning settings (they differ at {key})",
                          str(a.config_file))
    if a.criteria_file is not None and criteria_reference(a.criteria_file) \
            != settings.criteria_file:
        raise _refuse("--criteria", db, "with the paper's criteria" if not settings.criteria_file
                      else f"with --criteria {settings.criteria_file}", str(a.criteria_file))


def check_resume_args(run_dir: Path, settings: RunSettings, args: ResumeArgs) -> None:
    """Check what ``tune --resume run_dir`` was given against the run's ``settings`` (see the
    module docstring).

    Raises
    ------
    RvmsimError
        One line naming the option (or scene file), the run's store and what the run was
        made with.
    """
    db = run_dir / RUN_DB
    if args.force:
        raise RvmsimError(f"--force: not with --resume (--force replaces the run in a folder, "
                          f"--resume continues the one in {run_dir})")
    if args.out is not None and not _same_file(args.out, str(run_dir)):
        raise RvmsimError(f"--out {args.out}: --resume continues the run in {run_dir}, in its "
                          "own folder (give no --out)")
    if args.scenes:
        _check_scenes(db, settings, args.scenes)
    if args.only_supported and not settings.left_out:
        raise _refuse("--only-supported", db, "with every EC of its criteria (none left out)")
    _check_members(db, settings, args)
    _check_search(db, settings, args)
