"""Tuning: search space, strategies (one registry), objective, the search loop, the run model
and store, and tuning runs in run folders.

Modules: :mod:`~rvmsim.tune.space` (ParamRange, SearchSpace, default_space),
:mod:`~rvmsim.tune.strategies` (Strategy, the built-ins, STRATEGIES),
:mod:`~rvmsim.tune.objective` (score_vectors), :mod:`~rvmsim.tune.records` (the run model),
:mod:`~rvmsim.tune.store` (RunStore), :mod:`~rvmsim.tune.config` (TuningConfig),
:mod:`~rvmsim.tune.loop` (run_search, search_scene, the worker pool),
:mod:`~rvmsim.tune.folder` (reading run folders), :mod:`~rvmsim.tune.lock` (the writer
lock of run and sweep folders), :mod:`~rvmsim.tune.run` (tune).
"""

from __future__ import annotations

from .space import (
    ParamRange,
    SearchSpace,
    default_space,
)
from .strategies import (
    Strategy,
    GridToRandom,
    CmaEs,
    CmaEsSolved,
    RandomSearch,
    STRATEGIES,
    register_strategy,
    GridRandomSettings,
    CmaesSettings,
    CmaesSolvedSettings,
    RandomSettings,
    SEED_MAX,
    DEFAULT_STRATEGY,
    check_seed,
)
from .config import (
    TuningConfig,
    load_tuning_config,
    make_strategy,
)
from .records import (
    RunStatus,
    StopReason,
    EcOutcome,
    TrialRecord,
    RunSettings,
    RunState,
    params_json,
    ec_json,
    ecs_from_json,
    json_default,
)
from .objective import (
    OBJECTIVE_FLOOR,
    OBJECTIVES,
    PASS_WEIGHT,
    MAX_VIOLATION,
    violations,
    ScoredBatch,
    score_vectors,
)
from .store import (
    SqliteStore,
    RunStore,
    RUN_FORMAT,
)
from .loop import (
    SearchOutcome,
    run_search,
    BatchEvaluator,
    search_scene,
    candidate_evaluator,
    solver_for,
    strategy_scorer,
)
from .solve import EcSolver, SOLVED_PARAMS
from .lock import (
    FolderLock,
    Writer,
)
from .folder import (
    open_run,
    run_settings,
    run_state,
    run_lock,
    find_runs,
    is_run_folder,
    status_lines,
    rank_text,
    rank_params_text,
)
from .run import (
    tune,
    TuneResult,
    write_results,
    DISPLAY_SIZE,
    summary_lines,
    remove_run,
)

__all__ = [
    "ParamRange",
    "SearchSpace",
    "default_space",
    "Strategy",
    "GridToRandom",
    "CmaEs",
    "RandomSearch",
    "STRATEGIES",
    "register_strategy",
    "GridRandomSettings",
    "CmaesSettings",
    "CmaesSolvedSettings",
    "RandomSettings",
    "SEED_MAX",
    "DEFAULT_STRATEGY",
    "check_seed",
    "TuningConfig",
    "load_tuning_config",
    "make_strategy",
    "RunStatus",
    "StopReason",
    "EcOutcome",
    "TrialRecord",
    "RunSettings",
    "RunState",
    "params_json",
    "ec_json",
    "ecs_from_json",
    "json_default",
    "OBJECTIVE_FLOOR",
    "OBJECTIVES",
    "PASS_WEIGHT",
    "MAX_VIOLATION",
    "violations",
    "ScoredBatch",
    "score_vectors",
    "SqliteStore",
    "RunStore",
    "RUN_FORMAT",
    "SearchOutcome",
    "run_search",
    "BatchEvaluator",
    "search_scene",
    "solver_for",
    "strategy_scorer",
    "EcSolver",
    "SOLVED_PARAMS",
    "CmaEsSolved",
    "candidate_evaluator",
    "FolderLock",
    "Writer",
    "open_run",
    "run_settings",
    "run_state",
    "run_lock",
    "find_runs",
    "is_run_folder",
    "status_lines",
    "rank_text",
    "rank_params_text",
    "tune",
    "TuneResult",
    "write_results",
    "DISPLAY_SIZE",
    "summary_lines",
    "remove_run",
]
