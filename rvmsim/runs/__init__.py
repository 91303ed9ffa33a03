"""Tuning runs as data: the run model, its store, run folders and the diverse top-M.

What a run is and what it found, apart from how it searched (:mod:`rvmsim.tune`):

- :mod:`.records`: the run model, typed and frozen (:class:`RunSettings`, :class:`RunState`,
  :class:`RunStatus`, :class:`StopReason`, :class:`TrialRecord`, :class:`EcOutcome`,
  :class:`SceneRef`) and the JSON forms of its columns.
- :mod:`.store`: ``run.sqlite`` (:class:`RunStore`, on :class:`rvmsim.storage.SqliteStore`).
- :mod:`.diverse`: the diverse top-M (:class:`Candidate`, :func:`select_diverse`, the
  ``top/`` files).
- :mod:`.folder`: reading run folders (:func:`open_run`, :func:`run_inputs`,
  :func:`find_runs`, what ``rvmsim status`` and ``select`` print) and their writer lock.

They stand below :mod:`rvmsim.tune` (which writes runs) and above :mod:`rvmsim.search` (a run
records its tuning config and search space); the readers (``status``, ``select``, the report,
the console, sweeps) need nothing of the search.
"""

from __future__ import annotations

from .records import (
    RunStatus,
    StopReason,
    EcOutcome,
    TrialRecord,
    RunSettings,
    RunState,
    SceneRef,
    RunKind,
    RobustRecord,
    params_json,
    ec_json,
    ecs_from_json,
)
from .store import (
    RunStore,
    RUN_FORMAT,
)
from .diverse import (
    Candidate,
    select_diverse,
    differs_text,
    margins_of,
    normalised,
    POOLS,
    candidates_json,
    run_space,
    store_candidates,
    robust_keys,
    FLAT_SCORE,
)
from .folder import (
    RUN_DB,
    RUN_JSON,
    recorded_path,
    run_inputs,
    open_run,
    run_settings,
    run_state,
    run_lock,
    find_runs,
    is_run_folder,
    status_lines,
    rank_text,
    rank_params_text,
    diverse_candidates,
    write_top_files,
    top_file,
)

__all__ = [
    "RunStatus",
    "StopReason",
    "EcOutcome",
    "TrialRecord",
    "RunSettings",
    "RunState",
    "SceneRef",
    "RunKind",
    "RobustRecord",
    "params_json",
    "ec_json",
    "ecs_from_json",
    "RunStore",
    "RUN_FORMAT",
    "Candidate",
    "select_diverse",
    "differs_text",
    "margins_of",
    "normalised",
    "POOLS",
    "candidates_json",
    "run_space",
    "store_candidates",
    "robust_keys",
    "FLAT_SCORE",
    "RUN_DB",
    "RUN_JSON",
    "recorded_path",
    "run_inputs",
    "open_run",
    "run_settings",
    "run_state",
    "run_lock",
    "find_runs",
    "is_run_folder",
    "status_lines",
    "rank_text",
    "rank_params_text",
    "diverse_candidates",
    "write_top_files",
    "top_file",
]
