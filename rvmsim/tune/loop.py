"""The search loop: drive a strategy, evaluate its candidates (here or in worker processes),
store every batch, replay a stored run on resume.

:func:`search_scene` is the reusable core (one scene's rendered images → a searched run
store) that :func:`rvmsim.tune.tune`, a design-sweep point and a cluster task call;
:func:`run_search` is the loop itself, for any strategy and any batch evaluator.
"""

from __future__ import annotations

import dataclasses
import math
import time
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Sequence

import cv2
import numpy as np

from .._procs import start_pool, stop_pool, stop_requested
from ..criteria import Criteria
from ..errors import RvmsimError
from ..isp import IspParams, OutputSpec
from ..pipeline import ImageEvaluator, make_evaluator, record_output
from ..runs.records import StopReason, TrialRecord
from ..runs.store import RunStore
from ..search.config import TuningConfig, make_strategy
from ..search.space import SearchSpace
from ..search.strategies import Strategy
from .compensated import MembersCompensation as Compensation
from .members import (Aggregate, Member, MembersScorer, MembersSolver, check_members,
                      member_evaluators, parse_aggregate)
from .objective import ScoredBatch, score_vectors
from .requests import SearchOptions, SearchSettings
from .solve import EcSolver

if TYPE_CHECKING:
    from ..render import FisheyeImages
    from .compensated import MembersCompensation

__all__ = ["SearchOutcome", "run_search", "BatchEvaluator", "search_scene", "search_members",
           "members_scorer", "VectorScorer",
           "candidate_evaluator", "solver_for", "strategy_scorer"]


# ---------------------------------------------------------------------------- worker pool
_WORKER: Callable[[list[np.ndarray]], ScoredBatch] | None = None


class VectorScorer:
    """``xs → ScoredBatch`` on one evaluator (:func:`score_vectors`); picklable, what
    the worker processes of a one-scene search hold."""

    def __init__(self, evaluator: ImageEvaluator, space: SearchSpace,
                 solver: Callable[[IspParams], IspParams] | None = None,
                 objective: str = "log-score"):
        self.evaluator, self.space, self.solver, self.objective = (evaluator, space, solver,
                                                                   objective)

    def __call__(self, xs: list[np.ndarray]) -> ScoredBatch:
        return score_vectors(self.evaluator, self.space, xs, self.solver, self.objective)


def _init_worker(scorer: Callable[[list[np.ndarray]], ScoredBatch]) -> None:
    global _WORKER

    cv2.setNumThreads(1)
    _WORKER = scorer


def _work(xs: list[np.ndarray]) -> ScoredBatch:
    assert _WORKER is not None
    return _WORKER(xs)


def _chunks(n: int, workers: int, smallest: int = 8) -> list[tuple[int, int]]:
    """Guided self-scheduling: chunks of half the remaining work per worker, shrinking to
    ``smallest``, so that few large chunks keep overheads low and the small last ones keep
    the workers' finishing times close (a batch ends with its slowest chunk)."""
    out, start = [], 0
    while start < n:
        size = max(smallest, math.ceil((n - start) / (2 * workers)))
        out.append((start, min(n, start + size)))
        start += size
    return out


class BatchEvaluator:
    """Evaluates batches of candidate vectors in order, in this process or in ``workers``
    worker processes, each holding its own copy of the evaluator (the fisheye label image is
    1.2 MB).  Workers also score and serialise their candidates (:func:`score_vectors`), so
    the main process only stores them and steers the search.

    Workers come from :func:`rvmsim._procs.start_pool` (the pool batches use too).
    ``solver`` (:func:`solver_for`) sets the solved parameters of every candidate first;
    ``objective`` is the one the strategy maximises (:data:`rvmsim.tune.OBJECTIVES`).
    ``scorer`` replaces the one-evaluator scoring (``evaluator``, ``solver`` and
    ``objective`` are then unused): a :class:`~rvmsim.tune.MembersScorer`."""

    def __init__(self, evaluator: ImageEvaluator | None, space: SearchSpace,
                 workers: int = 1, solver: Callable[[IspParams], IspParams] | None = None,
                 objective: str = "log-score",
                 scorer: Callable[[list[np.ndarray]], ScoredBatch] | None = None):
        self.evaluator = evaluator
        self.space = space
        self.solver = solver
        self.objective = objective
        if scorer is None:
            if evaluator is None:
                raise ValueError("BatchEvaluator: give an evaluator or a scorer")
            scorer = VectorScorer(evaluator, space, solver, objective)
        self.scorer = scorer
        self.workers = max(1, workers)
        self.pool: ProcessPoolExecutor | None = None
        if self.workers > 1:
            self.pool = start_pool(self.workers, initializer=_init_worker,
                                   initargs=(scorer,))

    def __call__(self, xs: list[np.ndarray]) -> ScoredBatch:
        if self.pool is None:
            return self.scorer(xs)
        try:
            # submit, not map: map cancels the other chunks when one fails, and the pool,
            # stopped then, fails the cancelled ones with a traceback (Python 3.11)
            futures = [self.pool.submit(_work, xs[a:b]) for a, b in _chunks(len(xs), self.workers)]
            parts = [f.result() for f in futures]
        except BrokenProcessPool as err:  # a worker died, or could not start (its state did
            # not unpickle: e.g. a criteria plugin it cannot import); or a SIGTERM to the
            # process group ended it
            raise stop_requested() or RvmsimError(
                f"tuning worker processes failed ({err}); run with workers=1 to see the "
                "error in this process") from None
        return ScoredBatch(*([v for p in parts for v in getattr(p, f.name)]
                             for f in dataclasses.fields(ScoredBatch)))

    def close(self) -> None:
        if self.pool is not None:
            stop_pool(self.pool, now=True)
            self.pool = None


# ---------------------------------------------------------------------------- the loop
@dataclass(frozen=True)
class SearchOutcome:
    """What a search did: candidates evaluated now and replayed from the store, why it
    stopped, the best trial (highest EC score, then objective, then earliest), the search
    time (s), the space searched and the strategy's planned evaluations (None: unknown)."""

    evaluated: int
    replayed: int
    stopped: StopReason
    best: TrialRecord | None
    seconds: float
    space: SearchSpace
    total: int | None


def run_search(
    strategy: Strategy,
    evaluate_batch: Callable[[list[np.ndarray]], ScoredBatch],
    store: RunStore,
    *,
    max_time: float | None = None,
    target_score: float | None = None,
    on_batch: Callable[[int, float, str], None] | None = None,
) -> SearchOutcome:
    """Drive a strategy, evaluating new candidates and replaying stored ones.

    Trials already in ``store`` (a resumed run) are not evaluated again: the strategy is told
    their stored results, which makes it generate the same next candidates as the unbroken
    run did.  Each new batch is written to the store in one transaction before the strategy
    sees it.

    Parameters
    ----------
    evaluate_batch : callable
        list of candidate vectors (tuned values in ``strategy.space`` order) → their
        :class:`ScoredBatch`, in order: ``lambda xs: score_vectors(evaluator, space, xs)``,
        or :class:`rvmsim.tune.BatchEvaluator` (worker processes).
    max_time : float, optional
        Stop (resumably) after the batch during which this many seconds have passed.
    target_score : float, optional
        Stop once the best EC score reaches this.
    on_batch : callable, optional
        Called with (trials done, best EC score, stage) after every batch (progress bars).
    """
    t0 = time.perf_counter()
    stored = store.replay()
    # the solved parameters are set at evaluation, so the stored ones differ from the proposed
    compared = np.array([n not in strategy.solved for n in strategy.space.names])
    # best as (score, objective, -idx): highest score, then objective, then earliest
    best = max(((s, o, -i) for i, (s, o, _) in stored.items()), default=None)
    gen = strategy.batches()
    idx = evaluated = replayed = 0
    stopped = StopReason.DONE
    told: list[tuple[float, float]] | None = None
    space = strategy.space
    try:
        while True:
            stage, xs = gen.send(told) if told is not None else next(gen)
            indices = range(idx, idx + len(xs))
            if all(i in stored for i in indices):
                for i, x in zip(indices, xs):
                    if not np.allclose(space.vector(stored[i][2])[compared],
                                       np.clip(x, space.low, space.high)[compared],
                                       rtol=0, atol=1e-9):
                        raise RvmsimError(
                            f"{store.path}: trial {i} differs from what this strategy, seed and "
                            "configuration generate: resume with the run's own settings"
                        )
                told = [stored[i][:2] for i in indices]
                replayed += len(xs)
            else:
                b = evaluate_batch(list(xs))
                store.add_rows([
                    (i, stage, pj, s, o, int(ok), ej)
                    for i, pj, s, o, ok, ej in zip(indices, b.params_json, b.score, b.objective,
                                                   b.passed, b.ec_json)
                ], [(i, k, s, o, int(ok), ej) for i, ms in zip(indices, b.members)
                    for k, (s, o, ok, ej) in enumerate(ms)])
                told = list(zip(b.score, b.objective))
                evaluated += len(xs)
            for i, (s, o) in zip(indices, told):
                if best is None or (s, o) > best[:2]:
                    best = (s, o, -i)
            idx += len(xs)
            if on_batch is not None:
                on_batch(idx, best[0] if best else 0.0, stage)
            if evaluated and target_score is not None and best and best[0] >= target_score:
                stopped = StopReason.TARGET_SCORE
                break
            if evaluated and max_time is not None and time.perf_counter() - t0 >= max_time:
                stopped = StopReason.MAX_TIME
                break
    except StopIteration:  # the strategy has nothing more to propose: the search is done
        pass
    best_record = store.trials(-best[2], -best[2] + 1)[0] if best is not None else None
    return SearchOutcome(evaluated, replayed, stopped, best_record, time.perf_counter() - t0,
                         space, strategy.total())


# ---------------------------------------------------------------------------- the core
def solver_for(strategy: Strategy, evaluator: ImageEvaluator) -> EcSolver | None:
    """The :class:`EcSolver` a strategy that solves (``strategy.solves``) evaluates its
    candidates with, on ``evaluator``'s scene, output and criteria; it also tells the
    strategy which parameters are solved (``strategy.solved``).  None for other strategies."""
    if not strategy.solves:
        return None
    solver = EcSolver(evaluator.fisheye, evaluator.output, evaluator.criteria, strategy.space)
    strategy.solved = solver.names
    return solver


def strategy_scorer(strategy: Strategy, evaluator: ImageEvaluator
                    ) -> Callable[[list[np.ndarray]], ScoredBatch]:
    """``xs → ScoredBatch`` for ``strategy``'s candidates in this process, solved when the
    strategy solves (for benchmarks and custom loops; :func:`search_scene` is the full run)."""
    return BatchEvaluator(evaluator, strategy.space, 1, solver_for(strategy, evaluator),
                          strategy.objective)


def candidate_evaluator(images: FisheyeImages, config: TuningConfig,
                        criteria: Criteria) -> ImageEvaluator:
    """The evaluator tuning uses: ``images``' labels, the config's RVM output, ``criteria``
    (:func:`rvmsim.pipeline.make_evaluator`'s windowed path)."""
    return make_evaluator(images, config.output_spec(), criteria)


def search_scene(images: FisheyeImages, settings: SearchSettings, store: RunStore, *,
                 options: SearchOptions = SearchOptions(),
                 evaluator: ImageEvaluator | None = None) -> SearchOutcome:
    """Search one scene's ISP parameters: the core of a tuning run, a sweep point or a task.

    Builds the config's space on ``images.camera`` and the registered strategy, and runs
    it (:func:`run_search`) into ``store``, continuing what the store holds already.  Writes
    no files besides the store (``RunStore(":memory:")`` for none at all).

    Parameters
    ----------
    images : FisheyeImages
        The scene's rendered fisheye images (only the labels are used).
    settings : SearchSettings
        Config, criteria, strategy, seed, budget and starting points.
    store : RunStore
    options : SearchOptions
        Worker processes, stop conditions, progress callback.
    evaluator : ImageEvaluator, optional
        Made with :func:`candidate_evaluator` when not given (pass one to reuse it after the
        search, e.g. for a sensitivity analysis).
    """
    config = settings.config
    if isinstance(settings.strategy, Strategy):
        strat = settings.strategy
    else:
        space = config.space(images.camera)
        strat = make_strategy(settings.strategy, space, config, settings.seed, settings.budget,
                              [space.vector(p) for p in settings.starts])
    if evaluator is None:
        evaluator = candidate_evaluator(images, config, settings.criteria)
    return _drive(strat, _one_scene(strat, evaluator, options.workers), store, options)


def _one_scene(strat: Strategy, evaluator: ImageEvaluator, workers: int) -> BatchEvaluator:
    """The batch evaluator of a one-scene search: solved and scored as ``strat`` asks."""
    return BatchEvaluator(evaluator, strat.space, workers, solver_for(strat, evaluator),
                          strat.objective)


def _drive(strat: Strategy, batch_eval: BatchEvaluator, store: RunStore,
           options: SearchOptions) -> SearchOutcome:
    """:func:`run_search` with ``batch_eval``, whose worker processes are stopped after."""
    try:
        return run_search(strat, batch_eval, store, max_time=options.max_time,
                          target_score=options.target_score, on_batch=options.on_batch)
    finally:
        batch_eval.close()


def _members_compensation(members: Sequence[Member], settings: SearchSettings,
                          output: OutputSpec) -> MembersCompensation | None:
    """The per-car values of ``members`` under ``settings.compensation`` (None without)."""
    if settings.compensation is None:
        return None

    nominal = [i for i, m in enumerate(members) if m.station is None]
    return Compensation(settings.compensation,
                        record_output(settings.criteria, members[0].scene, output.mirror),
                        settings.criteria, [m.scene for m in members],
                        [m.station for m in members], nominal, [members[i] for i in nominal])


def search_members(members: Sequence[Member], settings: SearchSettings, store: RunStore, *,
                   options: SearchOptions = SearchOptions()) -> SearchOutcome:
    """Search one ISP parameter set for several members at once (shared tuning: one member
    per vehicle; robust tuning: one per variation sample), see :mod:`rvmsim.tune.members`.

    The space is the config's on the first member's camera (:func:`check_members`: every
    member has that sensor size); with one member this is :func:`search_scene` exactly.
    Each trial is stored with the aggregate verdicts, and each member's own in the store's
    ``members`` table.

    Parameters
    ----------
    members : sequence of Member
        The label images to judge every candidate on, the first the nominal one.
    settings : SearchSettings
        As for :func:`search_scene`, with how the members combine (``aggregate``, ``solve``,
        ``combine``); ``starts`` are not used.
    store : RunStore
    options : SearchOptions
    """
    check_members(members)
    agg = parse_aggregate(settings.aggregate)
    config, criteria = settings.config, settings.criteria
    if isinstance(settings.strategy, Strategy):
        strat = settings.strategy
    else:
        strat = make_strategy(settings.strategy, config.space(members[0].camera), config,
                              settings.seed, settings.budget)
    if len(members) == 1:
        evaluator = member_evaluators(members, config.output_spec(), criteria).evaluators[0]
        batch_eval = _one_scene(strat, evaluator, options.workers)
    else:
        batch_eval = BatchEvaluator(None, strat.space, options.workers,
                                    scorer=members_scorer(members, strat, settings, agg))
    return _drive(strat, batch_eval, store, options)


def members_scorer(members: Sequence[Member], strat: Strategy, settings: SearchSettings,
                   aggregate: Aggregate | None = None) -> MembersScorer:
    """The scorer of a search over several members (:class:`MembersScorer`): one evaluator
    per member (its own criteria or ``settings.criteria``) on the config's RVM output, and
    the members' sub-solves when ``strat`` solves (which it is told: ``strat.solved``).
    For :func:`search_members`, benchmarks and custom loops."""
    agg = aggregate or parse_aggregate(settings.aggregate)
    output = settings.config.output_spec()
    evaluators = member_evaluators(members, output, settings.criteria)
    solver = None
    comp = _members_compensation(members, settings, output)
    if strat.solves:
        # with compensation every car is corrected toward the nominal one: solve there
        solver = MembersSolver([EcSolver(ev.fisheye, output, m.criteria or settings.criteria,
                                         strat.space)
                                for m, ev in zip(members, evaluators.evaluators)],
                               "first" if comp is not None else settings.solve)
        strat.solved = solver.names
    return MembersScorer(evaluators, strat.space, solver, strat.objective, agg,
                         settings.combine, comp)
