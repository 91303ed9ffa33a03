"""Tuning: the search (objective, multi-member evaluation, closed-form sub-solves, the search
loop) and tuning runs (:func:`tune`: start, resume, shared and robust runs).

Modules: :mod:`~rvmsim.tune.objective` (score_vectors), :mod:`~rvmsim.tune.members`
(multi-member evaluation: shared and robust tuning), :mod:`~rvmsim.tune.solve` (closed-form
sub-solves), :mod:`~rvmsim.tune.loop` (run_search, search_scene, search_members, the worker
pool), :mod:`~rvmsim.tune.shared` and :mod:`~rvmsim.tune.robust` (shared and robust runs),
:mod:`~rvmsim.tune.run` (tune).

What is searched and how (the search space, the strategies, the tuning config) is
:mod:`rvmsim.search`, exported here too as the search API; what a run is and what it found
(records, ``run.sqlite``, run folders, the diverse top-M) is :mod:`rvmsim.runs`.
"""

from __future__ import annotations

from .objective import (
    OBJECTIVE_FLOOR,
    OBJECTIVES,
    PASS_WEIGHT,
    MAX_VIOLATION,
    violations,
    ScoredBatch,
    score_vectors,
    ParamsScores,
    score_params,
    check_objective,
)
from .members import (
    Member,
    Aggregate,
    parse_aggregate,
    MembersSolver,
    MembersScorer,
    check_members,
    check_cameras,
    worst_ec_json,
    member_evaluators,
    SOLVE_MODES,
    OBJECTIVE_COMBINE,
    COMBINES,
)
from .loop import (
    SearchOutcome,
    run_search,
    BatchEvaluator,
    search_scene,
    search_members,
    members_scorer,
    VectorScorer,
    candidate_evaluator,
    solver_for,
    strategy_scorer,
)
from .requests import (Markets, Robust, RunKindRequest, RunOptions, SearchOptions,
                       SearchSettings, Shared, TuneRequest)
from .solve import EcSolver
from .shared import write_member_results
from .new_run import load_shared_scenes, new_run_settings
from .run import (
    tune,
    resume,
    TuneResult,
    DISPLAY_SIZE,
)
from .results import remove_run, write_results
from .kinds import (Verdict, Built, TopRows, MemberSet, SingleSet, SharedSet, RobustSet,
                    CompensatedSet, MarketsSet, member_set)
from .summary import summary_lines

__all__ = [
    "OBJECTIVE_FLOOR",
    "OBJECTIVES",
    "PASS_WEIGHT",
    "MAX_VIOLATION",
    "violations",
    "ScoredBatch",
    "score_vectors",
    "ParamsScores",
    "score_params",
    "check_objective",
    "Member",
    "Aggregate",
    "parse_aggregate",
    "MembersSolver",
    "MembersScorer",
    "check_members",
    "check_cameras",
    "worst_ec_json",
    "member_evaluators",
    "SOLVE_MODES",
    "OBJECTIVE_COMBINE",
    "COMBINES",
    "SearchOutcome",
    "run_search",
    "BatchEvaluator",
    "search_scene",
    "search_members",
    "members_scorer",
    "VectorScorer",
    "candidate_evaluator",
    "solver_for",
    "strategy_scorer",
    "EcSolver",
    "SearchSettings",
    "SearchOptions",
    "TuneRequest",
    "Shared",
    "Robust",
    "Markets",
    "RunKindRequest",
    "RunOptions",
    "load_shared_scenes",
    "new_run_settings",
    "write_member_results",
    "tune",
    "resume",
    "TuneResult",
    "write_results",
    "DISPLAY_SIZE",
    "summary_lines",
    "Verdict",
    "Built",
    "MemberSet",
    "SingleSet",
    "SharedSet",
    "RobustSet",
    "CompensatedSet",
    "MarketsSet",
    "member_set",
    "TopRows",
    "remove_run",
]
