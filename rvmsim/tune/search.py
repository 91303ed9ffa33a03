"""Search the ISP parameters that maximise the EC score (paper, section VI).

Strategies
----------
``grid-random`` — the paper's grid-to-random search.  Coarse stage: a grid over the tuned
parameters, per parameter the values ``init + k·step`` inside its range.  The ``top_n`` best
grid points seed the fine stage: for each, ``trials`` random candidates drawn uniformly in
the *narrowed* range ``[x − step, x + step]`` (one coarse step around the seed, clipped to the
parameter's range).  The ``top_m`` best of everything are the result.

``cmaes`` — CMA-ES (the ``cmaes`` package) on the tuned parameters scaled to [0, 1], bounded,
seeded.  A tenth of the budget (at most 300) first explores uniformly at random; CMA-ES starts
from the best explored point and, each time it converges, restarts from the next best, until
``budget`` evaluations (default 8,000).  It
maximises ``Σ log(max(score_i, 1e-4))`` over the enabled ECs: the log of the EC score with a
floor per EC, so that a criterion stuck at ~0 still leaves a slope to climb.

``random`` — uniform random candidates over the ranges (a baseline).

Every strategy is a deterministic function of its seed and of the results it has been told,
so a run replayed from its stored results (``--resume``) continues exactly as an unbroken run.
"""

from __future__ import annotations

import itertools
import math
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Callable, Iterator, Sequence

import numpy as np

from ..camera import FisheyeCamera
from ..criteria.core import score_batch
from ..isp import IspParams, PARAM_SPECS, TUNED_BY_DEFAULT
from ..errors import RvmsimError
from .store import RunStore, TrialRecord, ec_json, params_json

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
]

_SPEC = {s.name: s for s in PARAM_SPECS}


@dataclass(frozen=True)
class ParamRange:
    """One tuned parameter: initial value, search range, coarse grid step and grid points.

    The coarse grid takes ``points`` values ``init + k·step`` centred on ``init``
    (k = −(points − 1)/2 … (points − 1)/2), dropping any outside [low, high]; the range also
    bounds the fine stage and the other strategies.
    """

    name: str
    init: float
    low: float
    high: float
    step: float
    points: int = 3

    def __post_init__(self) -> None:
        spec = _SPEC.get(self.name)
        if spec is None:
            raise ValueError(f"{self.name}: not an ISP parameter")
        if not spec.low <= self.low <= self.init <= self.high <= spec.high:
            raise ValueError(f"{self.name}: need {spec.low:g} <= low <= init <= high <= "
                             f"{spec.high:g}, got {self.low:g}, {self.init:g}, {self.high:g}")
        if self.step <= 0:
            raise ValueError(f"{self.name}: step must be > 0")
        if self.points < 1:
            raise ValueError(f"{self.name}: points must be >= 1")

    def grid(self) -> np.ndarray:
        """The coarse grid values of this parameter, ascending."""
        k = np.arange(self.points) - (self.points - 1) / 2.0
        values = self.init + self.step * k
        keep = (values >= self.low - 1e-9) & (values <= self.high + 1e-9)
        return np.clip(values[keep], self.low, self.high)


@dataclass(frozen=True)
class SearchSpace:
    """The tuned parameters and the values of the others."""

    ranges: tuple[ParamRange, ...]
    base: IspParams = field(default_factory=IspParams)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.ranges)

    @property
    def low(self) -> np.ndarray:
        return np.array([r.low for r in self.ranges])

    @property
    def high(self) -> np.ndarray:
        return np.array([r.high for r in self.ranges])

    @property
    def step(self) -> np.ndarray:
        return np.array([r.step for r in self.ranges])

    def params(self, x: Sequence[float]) -> IspParams:
        """ISP parameters for a vector of tuned values (clipped to the ranges)."""
        x = np.clip(np.asarray(x, dtype=np.float64), self.low, self.high)
        return self.base.replace(**{n: float(v) for n, v in zip(self.names, x)})

    def vector(self, p: IspParams) -> np.ndarray:
        return np.array([getattr(p, n) for n in self.names])

    def grid_size(self) -> int:
        return int(np.prod([len(r.grid()) for r in self.ranges]))

    def grid(self) -> Iterator[np.ndarray]:
        """The coarse grid, in a fixed order (last parameter fastest)."""
        for combo in itertools.product(*(r.grid() for r in self.ranges)):
            yield np.array(combo)

    def narrowed(self, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The fine stage's range around a coarse result: one step each way, clipped."""
        return np.maximum(centre - self.step, self.low), np.minimum(centre + self.step, self.high)


def default_space(camera: FisheyeCamera, names: Sequence[str] = TUNED_BY_DEFAULT) -> SearchSpace:
    """The nine parameters the paper tunes, with initial values fitted to the camera.

    RAD starts at the radius the lens gives 180° (fx·π/2, which with FOV 180 makes the ISP's
    lens model the real one for an equidistance lens); H/V shift start at the principal
    point's offset.  Ranges cover views from nearly uncorrected to strongly corrected; the
    coarse grid takes 3 values per parameter (3⁹ = 19,683 candidates).
    """
    rad0 = camera.fx * math.pi / 2
    h0 = camera.cx - (camera.width - 1) / 2
    v0 = camera.cy - (camera.height - 1) / 2
    q = camera.width / 1280.0  # pixel-valued ranges follow the sensor size
    table = {
        "fov": (180.0, 150.0, 210.0, 20.0),
        "rad": (rad0, 0.55 * rad0, 1.45 * rad0, 0.3 * rad0),
        "h_shift": (h0, h0 - 60 * q, h0 + 60 * q, 30 * q),
        "v_shift": (v0, v0 - 160 * q, v0 + 160 * q, 80 * q),
        "zoom": (0.7, 0.25, 1.45, 0.3),
        "adv_h_shift": (0.0, -0.4, 0.4, 0.2),
        "adv_v_shift": (0.0, -0.8, 0.8, 0.4),
        "adv_h_scale": (1.0, 0.5, 1.8, 0.3),
        "adv_v_scale": (1.2, 0.6, 2.0, 0.4),
    }
    ranges = []
    for n in names:
        if n in table:
            init, lo, hi, step = table[n]
        else:
            spec = _SPEC[n]
            init, lo, hi, step = spec.default, spec.low, spec.high, (spec.high - spec.low) / 4
        ranges.append(ParamRange(n, init, lo, hi, step))
    return SearchSpace(tuple(ranges))


# ---------------------------------------------------------------------------- objective
OBJECTIVE_FLOOR = 1e-4


# ---------------------------------------------------------------------------- strategies
class Strategy(ABC):
    """Produces batches of candidate vectors; told each batch's objectives before the next.

    ``batches`` is a generator: it yields ``(stage, xs)`` and receives, through ``send``,
    the list of (EC score, objective) pairs of ``xs``.  It must be deterministic.
    """

    name = "strategy"

    def __init__(self, space: SearchSpace, *, seed: int = 0):
        self.space = space
        self.seed = seed

    @abstractmethod
    def batches(self) -> Iterator[tuple[str, list[np.ndarray]]]: ...

    def total(self) -> int | None:
        """Evaluations the strategy will make, when known in advance."""
        return None


class GridToRandom(Strategy):
    """The paper's grid-to-random search (see the module docstring)."""

    name = "grid-random"

    def __init__(self, space: SearchSpace, *, seed: int = 0, top_n: int = 2, trials: int = 20000,
                 batch: int = 1024):
        super().__init__(space, seed=seed)
        if top_n < 1 or trials < 0:
            raise ValueError("top_n must be >= 1 and trials >= 0")
        self.top_n, self.trials, self.batch = top_n, trials, batch

    def total(self) -> int:
        return self.space.grid_size() + self.top_n * self.trials

    def batches(self):
        coarse: list[tuple[float, float, int, np.ndarray]] = []
        grid = self.space.grid()
        idx = 0
        while True:
            xs = list(itertools.islice(grid, self.batch))
            if not xs:
                break
            told = yield "coarse", xs
            for x, (score, obj) in zip(xs, told):
                coarse.append((score, obj, idx, x))
                idx += 1
        coarse.sort(key=lambda t: (-t[0], -t[1], t[2]))
        for n, (_, _, _, centre) in enumerate(coarse[: self.top_n]):
            lo, hi = self.space.narrowed(centre)
            rng = np.random.default_rng([self.seed, n])
            left = self.trials
            while left > 0:
                k = min(self.batch, left)
                xs = list(rng.uniform(lo, hi, size=(k, len(lo))))
                yield f"fine-{n + 1}", xs
                left -= k


class RandomSearch(Strategy):
    """Uniform random candidates over the ranges."""

    name = "random"

    def __init__(self, space: SearchSpace, *, seed: int = 0, budget: int = 2000, batch: int = 256):
        super().__init__(space, seed=seed)
        self.budget, self.batch = budget, batch

    def total(self) -> int:
        return self.budget

    def batches(self):
        rng = np.random.default_rng(self.seed)
        left = self.budget
        while left > 0:
            k = min(self.batch, left)
            yield "random", list(rng.uniform(self.space.low, self.space.high,
                                             size=(k, len(self.space.ranges))))
            left -= k


class CmaEs(Strategy):
    """Bounded CMA-ES with restarts (see the module docstring).

    The first ``explore`` evaluations (default: a tenth of the budget, at most 300) are
    uniform random candidates; CMA-ES then starts from the best of them, and each restart
    from the next best explored point, so the restarts begin in different basins that are
    already known to be good."""

    name = "cmaes"

    def __init__(self, space: SearchSpace, *, seed: int = 0, budget: int = 8000,
                 sigma0: float = 0.3, popsize: int | None = None, explore: int | None = None):
        super().__init__(space, seed=seed)
        self.budget, self.sigma0, self.popsize = budget, sigma0, popsize
        self.explore = min(budget // 10, 300) if explore is None else explore

    def total(self) -> int:
        return self.budget

    def batches(self):
        from cmaes import CMA

        lo, hi = self.space.low, self.space.high
        span = hi - lo
        dim = len(lo)
        rng = np.random.default_rng([self.seed, 7])
        starts = [np.array([(r.init - r.low) / (r.high - r.low) for r in self.space.ranges])]
        used = 0
        if self.explore > 0:
            us = rng.uniform(0.0, 1.0, size=(self.explore, dim))
            told = yield "explore", [lo + u * span for u in us]
            used += len(us)
            order = sorted(range(len(us)), key=lambda i: (-told[i][1], i))
            starts = [us[i] for i in order] + starts
        restart = 0
        while used < self.budget:
            start = starts[restart] if restart < len(starts) else rng.uniform(0.1, 0.9, dim)
            opt = CMA(mean=np.clip(start, 0.0, 1.0), sigma=self.sigma0,
                      bounds=np.tile([0.0, 1.0], (dim, 1)), seed=self.seed * 1000 + restart,
                      population_size=self.popsize)
            while used < self.budget and not opt.should_stop():
                us = [opt.ask() for _ in range(opt.population_size)]
                told = yield f"cmaes-{restart + 1}", [lo + u * span for u in us]
                used += len(us)
                opt.tell([(u, -obj) for u, (_, obj) in zip(us, told)])
            restart += 1


STRATEGIES: dict[str, type[Strategy]] = {
    GridToRandom.name: GridToRandom, CmaEs.name: CmaEs, RandomSearch.name: RandomSearch,
}


# ---------------------------------------------------------------------------- the loop
@dataclass(frozen=True)
class SearchOutcome:
    evaluated: int
    replayed: int
    stopped: str  # "done", "max-time", "target-score"
    best: TrialRecord | None
    seconds: float


@dataclass(frozen=True)
class ScoredBatch:
    """A batch of evaluated candidates, ready to store: what ``evaluate_batch`` returns to
    :func:`run_search`.  Built by :func:`score_vectors` (in worker processes, when tuning
    runs them, so that the main process only stores and steers)."""

    score: list[float]
    objective: list[float]
    passed: list[bool]
    params_json: list[str]
    ec_json: list[str]


def score_vectors(evaluator, space: SearchSpace, xs: Sequence[np.ndarray]) -> ScoredBatch:
    """Evaluate candidate vectors of ``space`` with a
    :class:`~rvmsim.evaluator.CandidateEvaluator`, scored and serialised for the store."""
    params = [space.params(x) for x in xs]
    ids = evaluator.criteria.ids
    values = np.array([evaluator.values(p) for p in params]).reshape(len(params), len(ids))
    b = score_batch(values, evaluator.criteria)
    ecs = [ec_json(ids, v, s, o) for v, s, o in zip(b.values.tolist(), b.scores.tolist(),
                                                b.passed.tolist())]
    return ScoredBatch(b.score.tolist(), b.objective(OBJECTIVE_FLOOR).tolist(),
                       b.all_passed.tolist(), [params_json(p) for p in params], ecs)


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
    stored = {r.idx: (r.score, r.objective, r.params) for r in store.trials()}
    # best as (score, objective, -idx): highest score, then objective, then earliest
    best = max(((s, o, -i) for i, (s, o, _) in stored.items()), default=None)
    gen = strategy.batches()
    idx = evaluated = replayed = 0
    stopped = "done"
    told = None
    space = strategy.space
    try:
        while True:
            stage, xs = gen.send(told) if told is not None else next(gen)
            indices = range(idx, idx + len(xs))
            if all(i in stored for i in indices):
                for i, x in zip(indices, xs):
                    if not np.allclose(space.vector(stored[i][2]), np.clip(x, space.low, space.high),
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
                ])
                told = list(zip(b.score, b.objective))
                evaluated += len(xs)
            for i, (s, o) in zip(indices, told):
                if best is None or (s, o) > best[:2]:
                    best = (s, o, -i)
            idx += len(xs)
            if on_batch is not None:
                on_batch(idx, best[0] if best else 0.0, stage)
            if evaluated and target_score is not None and best and best[0] >= target_score:
                stopped = "target-score"
                break
            if evaluated and max_time is not None and time.perf_counter() - t0 >= max_time:
                stopped = "max-time"
                break
    except StopIteration:
        pass
    best_record = store.trials(-best[2], -best[2] + 1)[0] if best is not None else None
    return SearchOutcome(evaluated, replayed, stopped, best_record, time.perf_counter() - t0)
