"""Tuning: search space, strategies, the run loop and the run store."""

from __future__ import annotations

from .search import (
    ParamRange,
    SearchSpace,
    default_space,
    Strategy,
    GridToRandom,
    CmaEs,
    RandomSearch,
    STRATEGIES,
    run_search,
    SearchOutcome,
    ScoredBatch,
    score_vectors,
)
from .store import (
    SqliteStore,
    RunStore,
    TrialRecord,
    params_json,
    ec_json,
    json_default,
)
from .loop import (
    TuningConfig,
    load_tuning_config,
    make_strategy,
    tune,
    TuneResult,
    write_results,
    tune_task,
    portable_scene_doc,
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
    "run_search",
    "SearchOutcome",
    "ScoredBatch",
    "score_vectors",
    "SqliteStore",
    "RunStore",
    "TrialRecord",
    "params_json",
    "ec_json",
    "json_default",
    "TuningConfig",
    "load_tuning_config",
    "make_strategy",
    "tune",
    "TuneResult",
    "write_results",
    "tune_task",
    "portable_scene_doc",
]
