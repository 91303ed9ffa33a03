"""Reading a run folder: its store, its settings (also of runs of rvmsim 0.1), what
``rvmsim status`` and ``rvmsim select`` print.

A run folder holds ``run.sqlite`` (the truth: settings, state, trials), ``run.json`` (a
human-readable export of the settings), ``top/`` (the diverse top-M: ``rank_K.yaml`` and
``candidates.json``, see :mod:`rvmsim.runs.diverse`) and ``best/``.  Runs written by rvmsim 0.1
kept their settings in ``run.json`` only and their status as free text; they are read as they
are (:func:`run_settings`), and a resumed one is brought to the current format.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from ..criteria import bundled_criteria_text
from .._io import read_json_file
from ..errors import ParamsFileError, ResultFileError, RvmsimError
from ..isp import IspParams, OutputSpec, load_params, params_to_dict
from ..storage import FolderLock, json_default
from .diverse import Candidate, candidates_json, store_candidates
from .records import RunSettings, RunState, RunStatus, TrialRecord
from .store import RunStore

if TYPE_CHECKING:
    from ..criteria import Criteria

__all__ = ["RUN_DB", "RUN_JSON", "recorded_path", "run_inputs", "open_run", "run_settings",
           "json_difference", "run_json_disagreement",
           "run_state", "run_lock", "find_runs", "is_run_folder", "status_lines", "rank_text",
           "rank_params_text", "diverse_candidates", "write_top_files", "top_file"]

RUN_DB = "run.sqlite"
RUN_JSON = "run.json"


def run_lock(run_dir: str | Path) -> FolderLock:
    """The writer lock of the run folder ``run_dir`` (``run.lock``, its writer in
    ``run.pid``; see :mod:`rvmsim.storage.lock`)."""
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
        One line: no such folder, no ``run.sqlite`` in it, or not a readable one.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():  # the words signoff and the console use too
        raise RvmsimError(f"{run_dir}: no such run folder")
    if not is_run_folder(run_dir):
        raise RvmsimError(f"{run_dir}: not a run folder (no {RUN_DB} in it)")
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
        doc = read_json_file(run_json, ResultFileError, what=RUN_JSON)
        return RunSettings.from_json({**doc, "config": _legacy_config(doc.get("config") or {})})
    except ResultFileError as err:  # over the JSON limits, or not JSON
        raise RvmsimError(f"{run_json}: not a readable {RUN_JSON} ({err.message}); restore it, "
                          "or start a new run") from None
    except (ValueError, KeyError, TypeError, AttributeError) as err:
        msg = f"{run_json}: not a readable {RUN_JSON} ({err}); restore it, or start a new run"
        raise RvmsimError(" ".join(msg.split())) from None


def json_difference(a: Any, b: Any, key: str = "", *, a_keys: bool = False) -> str:
    """The dotted key of the first difference between two JSON documents (objects compared
    key by key, in ``a``'s order, then ``b``'s extra keys unless ``a_keys``: then only the
    keys ``a`` has); '' when they are equal."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in list(a) + ([] if a_keys else [k for k in b if k not in a]):
            sub = json_difference(a.get(k), b.get(k), f"{key}.{k}" if key else str(k),
                                  a_keys=a_keys)
            if sub:
                return sub
        return ""
    return "" if a == b else (key or "(the whole document)")


def _at(doc: Any, key: str) -> Any:
    for part in key.split("."):
        doc = doc.get(part) if isinstance(doc, dict) else None
    return doc


def _short(value: Any, limit: int = 60) -> str:
    text = json.dumps(value, default=json_default)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def run_json_disagreement(run_dir: str | Path, settings: RunSettings) -> str | None:
    """Where the run's ``run.json`` disagrees with the settings in its store, as the start of
    one line (``RUN/run.json: budget is 80 but RUN/run.sqlite holds 40``); None when
    run.json is absent or each of its keys says what the store holds.  The store is the truth (``tune
    --resume``, ``report``, ``select`` read it); run.json is its export for people, so an
    edit there changes nothing, and ``status`` and ``tune --resume`` say so."""
    path = Path(run_dir) / RUN_JSON
    if not path.is_file():
        return None
    stored = json.loads(json.dumps(settings.as_json(), default=json_default))
    try:
        doc = read_json_file(path, ResultFileError, what=RUN_JSON)
    except RvmsimError as err:  # over the JSON limits, or not JSON: said as it is
        return str(err)
    # only the keys run.json has: one written by an older rvmsim may lack newer defaults
    key = json_difference(doc, stored, a_keys=True)
    if not key:
        return None
    if key == "(the whole document)":
        return f"{path}: holds {_short(doc)}, not the settings {Path(run_dir) / RUN_DB} holds"
    return (f"{path}: {key} is {_short(_at(doc, key))} but {Path(run_dir) / RUN_DB} holds "
            f"{_short(_at(stored, key))}")


def recorded_path(recorded: str, run_dir: Path) -> Path | None:
    """A file as ``tune`` recorded it: absolute, or relative to the current folder (where
    tune usually ran), the run folder or its parent; None when it is not there."""
    p = Path(recorded).expanduser()
    if p.is_absolute():
        return p if p.is_file() else None
    for cand in (p, run_dir / p, run_dir.parent / p):
        if cand.is_file():
            return cand
    return None


def run_inputs(run_dir: str | Path, settings: RunSettings) -> tuple[Path, Path | None]:
    """The run's scene file and its criteria (a bundled set's name, as a path, or the file;
    None: the paper's), found as :func:`recorded_path` finds them.

    Raises
    ------
    RvmsimError
        One line naming the scene or criteria file that is gone.
    """

    run_dir = Path(run_dir)
    scene_file = recorded_path(settings.scene, run_dir)
    if scene_file is None:
        raise RvmsimError(f"{run_dir}: scene file {settings.scene} not found")
    if not settings.criteria_file:
        return scene_file, None
    if bundled_criteria_text(settings.criteria_file) is not None:
        return scene_file, Path(settings.criteria_file)
    crit_file = recorded_path(settings.criteria_file, run_dir)
    if crit_file is None:
        raise RvmsimError(f"{run_dir}: criteria file {settings.criteria_file} not found")
    return scene_file, crit_file


def diverse_candidates(run_dir: str | Path, m: int | None = None,
                       min_distance: float | None = None, *, by_score: bool = False
                       ) -> list[Candidate]:
    """The diverse top-M of the run in ``run_dir`` (:mod:`rvmsim.runs.diverse`): what its
    ``top/`` files, its report's gallery, ``rvmsim status`` and ``rvmsim select`` offer.
    ``m`` and ``min_distance`` default to the run's tuning config; ``by_score``: the M best
    by EC score instead (the plain order).

    Raises
    ------
    RvmsimError
        One line: not a run, unreadable settings or trials, its criteria file (or, for a
        run of an earlier version, its scene file) unreadable.
    """
    return [c for c, _ in _run_candidates(run_dir, m, min_distance, by_score)]


def _run_candidates(run_dir: str | Path, m: int | None, min_distance: float | None,
                    by_score: bool) -> list[tuple[Candidate, TrialRecord]]:
    store = open_run(run_dir)
    try:
        return store_candidates(store, run_settings(run_dir, store), m, min_distance,
                                by_score=by_score)
    finally:
        store.close()


def status_lines(run_dir: str | Path, top_m: int | None = None, *, by_score: bool = False,
                 min_distance: float | None = None) -> list[str]:
    """What ``rvmsim status`` prints: the state and the current top-M (while it runs, too)
    as :func:`diverse_candidates` chooses them (``by_score``: the M best by score), each
    after rank 1 with its distance to rank 1 and how it differs; for a shared run also its
    scenes, and each top candidate's per-scene EC scores.  ``top_m``: M (default: the
    run's, ``diverse.m`` or ``top_m`` of its tuning config)."""
    store = open_run(run_dir)
    try:
        state = run_state(run_dir, store)
        n = store.count()
        meta = store.meta()
        scenes, aggregate = meta.get("scenes"), meta.get("aggregate")
        markets = meta.get("markets")
        top: list[tuple[int, TrialRecord, str]] = []
        note = ""
        differs = None
        heading: list[str] = []
        try:
            settings = run_settings(run_dir, store)
            top = [(c.rank, rec, "" if not c.differs else f"  (distance {c.distance:.2f}: "
                    f"{c.differs})") for c, rec in store_candidates(
                        store, settings, top_m, min_distance, by_score=by_score)]
            dmin = settings.config.diverse.min_distance if min_distance is None else min_distance
            heading = _list_heading(len(top), dmin, by_score)
            if store.settings() is not None:  # not a run of rvmsim 0.1 (run.json its truth)
                differs = run_json_disagreement(run_dir, settings)
        except RvmsimError as err:  # status needs only the store: say why, show by score
            note = f"top candidates by EC score (the diverse top-M needs: {err})"
            top = [(k, rec, "") for k, rec in enumerate(store.top(top_m or 5), start=1)]
        members = {rec.idx: [m[0] for m in store.member_results(rec.idx)] for _, rec, _ in top}
    finally:
        store.close()
    total = "" if state.total is None else f" / {state.total}"
    lines = [f"{run_dir}: {state.text}, strategy {state.strategy}, {n}{total} evaluations"]
    if isinstance(scenes, list) and scenes:
        names = ", ".join(str(r.get("vehicle") if isinstance(r, dict) else r) for r in scenes)
        if isinstance(markets, list) and markets:
            per = f"{len(scenes)} scene{'s' if len(scenes) > 1 else ''} ({names})"
            lines.append(f"  one setting for {len(markets)} markets ({', '.join(map(str, markets))})"
                         f" of {per}; EC score: their {aggregate}")
        else:
            lines.append(f"  shared by {len(scenes)} scenes ({names}); EC score: their "
                         f"{aggregate}")
    if note:
        lines.append("  " + " ".join(note.split()))
    if differs:
        lines.append(f"  {differs}: the settings live in {RUN_DB} and are used; {RUN_JSON} "
                     "only exports them (an edit there changes nothing)")
    lines += heading
    for rank, rec, how in top:
        fails = rec.failing()
        each = "" if not members[rec.idx] else "  [" + ", ".join(
            f"{m:.4g}" for m in members[rec.idx]) + "]"
        lines.append(f"  #{rank}  EC score {rec.score:.4g}  trial {rec.idx:>6} "
                     f"({rec.stage})  {'all pass' if not fails else 'fails ' + ','.join(fails)}"
                     f"{each}{how}")
    return lines


def _list_heading(m: int, min_distance: float, by_score: bool) -> list[str]:
    """What :func:`status_lines`' list is and what its columns say."""
    if by_score:
        return [f"  the {m} best trials by EC score (--by-score)"]
    return [f"  the diverse top-{m}, not in score order: #1 is the best trial; each next one is "
            f"the best left at least {min_distance:g} of each tuned parameter's search span "
            "from every one above it",
            "  (distance: to #1, in those spans; then how it differs from #1, its values "
            "beside #1's)"]


def rank_text(rec: TrialRecord, rank: int, output: OutputSpec, vehicle: str | None = None,
              differs: str = "", judged_at: OutputSpec | None = None) -> str:
    """A trial as a params file (YAML, loadable by :func:`rvmsim.isp.load_params`) with a
    comment line naming its rank, EC score, trial and stage (and, given ``differs``, a
    second one saying how it differs from rank 1; given ``judged_at``, the RVM image of
    record its verdict refers to, also as ``output.judged_at``)."""

    of = "" if vehicle is None else f" of {vehicle}"
    how = "" if not differs else f"# differs from rank 1: {' '.join(differs.split())}\n"
    judged = ("" if judged_at is None else
              f"# judged at the RVM image of record, {judged_at.width}x{judged_at.height} px\n")
    return (f"# rank {rank}{of}: EC score {rec.score:.6g} (trial {rec.idx}, {rec.stage})\n"
            + how + judged + yaml.safe_dump(params_to_dict(rec.params, output,
                                                           judged_at=judged_at),
                                            sort_keys=False))


def rank_params_text(run_dir: str | Path, rank: int = 1, *, by_score: bool = False,
                     min_distance: float | None = None) -> str:
    """The rank-K parameter set of a run as a params file (what ``rvmsim select`` writes),
    at the run's tuning output size: rank K of :func:`diverse_candidates` (``by_score``: of
    the plain score order); ranks beyond the run's M continue the same list.

    Raises
    ------
    RvmsimError
        One line: not a run, unreadable settings, or fewer than ``rank`` candidates.
    """
    store = open_run(run_dir)
    try:
        settings = run_settings(run_dir, store)
        top = store_candidates(store, settings, max(rank, settings.config.diverse_m),
                               min_distance, by_score=by_score)
    finally:
        store.close()
    if len(top) < rank:
        apart = "" if by_score else (
            f" at least {min_distance or settings.config.diverse.min_distance:g} apart "
            "(see --by-score)")
        raise RvmsimError(f"{run_dir}: only {len(top)} candidates{apart}, no rank {rank}")
    cand, rec = top[rank - 1]
    return rank_text(rec, rank, settings.config.output_spec(), differs=cand.differs,
                     judged_at=settings.record_output())


def _top_path(run_dir: str | Path, rank: int) -> Path:
    """Where :func:`write_top_files` writes rank ``rank``'s params file."""
    return Path(run_dir) / "top" / f"rank_{rank}.yaml"


def top_file(run_dir: str | Path, rank: int, params: IspParams,
             output: OutputSpec) -> Path | None:
    """The run's ``top/rank_K.yaml`` (:func:`write_top_files`) when it holds ``params``
    and ``output``, else None: absent, unreadable, or of another selection."""
    path = _top_path(run_dir, rank)
    try:
        held, held_output = load_params(path)
    except (ParamsFileError, OSError):
        return None
    return path if held == params and held_output == output else None


def write_top_files(run_dir: str | Path, store: RunStore, settings: RunSettings,
                    vehicle: str | None = None, criteria: Criteria | None = None) -> list[Candidate]:
    """``top/rank_K.yaml`` (params files, each with its ``differs`` line as a comment) and
    ``top/candidates.json`` for the run's diverse top-M; any ``rank_K.yaml`` of an earlier
    top-M beyond them removed.  Returns the candidates."""
    cfg = settings.config
    pairs = store_candidates(store, settings, criteria=criteria)
    top = Path(run_dir) / "top"
    top.mkdir(parents=True, exist_ok=True)
    out = cfg.output_spec()
    for cand, rec in pairs:
        _top_path(run_dir, cand.rank).write_text(
            rank_text(rec, cand.rank, out, vehicle, cand.differs, settings.record_output()),
            encoding="utf-8")
    for old in top.glob("rank_*.yaml"):
        k = old.stem[len("rank_"):]
        if not k.isdigit() or not 1 <= int(k) <= len(pairs):
            old.unlink()
    cands = [c for c, _ in pairs]
    (top / "candidates.json").write_text(json.dumps(candidates_json(
        cands, cfg.diverse_m, cfg.diverse.min_distance, cfg.diverse.score_tolerance),
        indent=2, default=json_default), encoding="utf-8")
    return cands
