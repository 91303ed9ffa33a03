"""Search strategies and their registry (paper, section VI).

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
A seed is an integer from 0 to :data:`SEED_MAX` (:func:`check_seed`); the random streams of a
strategy's stages are numpy ``SeedSequence`` children of it (``[seed, n]``), and a CMA-ES
restart's seed is ``seed·1000 + restart`` where that fits numpy's 32-bit seeds (every seed
up to 4,294,967, as before) and a ``SeedSequence([seed, restart])`` draw above.

Registry
--------
:data:`STRATEGIES` maps each strategy's ``name`` to its class; a class registers itself with
:func:`register_strategy` and names its tuning-config section (``section``, a key of
:class:`~rvmsim.search.TuningConfig`) and that section's pydantic model (``Settings``, which
forbids keys the strategy does not use).  ``rvmsim tune --strategy``, the tuning config and
the sweep file all read the registry.
"""

from __future__ import annotations

import itertools
import math
from abc import ABC, abstractmethod
from typing import Annotated, ClassVar, Generator, Sequence, TypeVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ..errors import RvmsimError
from .space import SearchSpace

__all__ = ["Strategy", "GridToRandom", "RandomSearch", "CmaEs", "CmaEsSolved", "STRATEGIES",
           "register_strategy", "NoSettings", "GridRandomSettings", "CmaesSettings", "RandomSettings",
           "CmaesSolvedSettings", "Batches", "Told", "SEED_MAX", "check_seed", "DEFAULT_STRATEGY"]

#: The strategy ``rvmsim tune``, ``batch`` and ``sweep`` use when none is named: the most
#: reliable one by ``tools/bench_reliability.py`` (docs/guide.md, "Reliability").
DEFAULT_STRATEGY = "cmaes-solved"

#: The largest seed: numpy's 32-bit seed range, so a seed means the same to every generator.
SEED_MAX = 2**32 - 1


def check_seed(seed: object, name: str = "--seed") -> int:
    """``seed`` if it is a seed (an integer from 0 to :data:`SEED_MAX`).

    Raises
    ------
    RvmsimError
        One line naming ``name`` (the option, or the file and key it came from) and the range.
    """
    if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) \
            and 0 <= seed <= SEED_MAX:
        return int(seed)
    raise RvmsimError(f"{name} {seed!r}: not a seed; give an integer from 0 to {SEED_MAX}")


def _cma_seed(seed: int, restart: int) -> int:
    """The seed of CMA-ES restart ``restart`` (see the module docstring): within numpy's
    32-bit range for every seed and restart."""
    old = seed * 1000 + restart
    if old <= SEED_MAX:
        return old
    return int(np.random.SeedSequence([seed, restart]).generate_state(1)[0])

#: What a strategy is told about a batch: (EC score, objective) per candidate, in order.
Told = list[tuple[float, float]]
#: A strategy's generator: yields (stage, candidate vectors), receives their :data:`Told`.
Batches = Generator[tuple[str, list[np.ndarray]], Told, None]


# ---------------------------------------------------------------------------- settings
class NoSettings(BaseModel):
    """The settings of a strategy that has none."""

    model_config = ConfigDict(extra="forbid")


class GridRandomSettings(BaseModel):
    """``grid_random:`` — seeds of the fine stage (N) and fine trials per seed (T)."""

    model_config = ConfigDict(extra="forbid")
    top_n: Annotated[int, Field(ge=1)] = 2
    trials: Annotated[int, Field(ge=0)] = 20000


class CmaesSettings(BaseModel):
    """``cmaes:`` — evaluations and the initial step size (in the [0, 1]-scaled space)."""

    model_config = ConfigDict(extra="forbid")
    budget: Annotated[int, Field(ge=1)] = 8000
    sigma0: Annotated[float, Field(gt=0, le=1)] = 0.3


class CmaesSolvedSettings(BaseModel):
    """``cmaes_solved:`` — evaluations, the initial step size, the random explore points
    before CMA-ES starts, and the population's growth at each restart (IPOP; 1: none)."""

    model_config = ConfigDict(extra="forbid")
    budget: Annotated[int, Field(ge=1)] = 8000
    sigma0: Annotated[float, Field(gt=0, le=1)] = 0.3
    explore: Annotated[int, Field(ge=0)] = 100
    restart_growth: Annotated[float, Field(ge=1, le=4)] = 2.0


class RandomSettings(BaseModel):
    """``random:`` — evaluations."""

    model_config = ConfigDict(extra="forbid")
    budget: Annotated[int, Field(ge=1)] = 2000


_S = TypeVar("_S", bound=BaseModel)


def _settings(settings: BaseModel, kind: type[_S]) -> _S:
    if not isinstance(settings, kind):
        raise TypeError(f"expected {kind.__name__}, got {type(settings).__name__}")
    return settings


# ---------------------------------------------------------------------------- strategies
class Strategy(ABC):
    """Produces batches of candidate vectors; told each batch's objectives before the next.

    ``batches`` is a generator: it yields ``(stage, xs)`` and receives, through ``send``,
    the list of (EC score, objective) pairs of ``xs``.  It must be deterministic.
    """

    #: The registry key (``--strategy``).
    name: ClassVar[str] = "strategy"
    #: One line for ``--help``.
    summary: ClassVar[str] = ""
    #: The tuning config's key of this strategy's settings ("": none, the defaults of
    #: ``Settings`` are used), and their model.
    section: ClassVar[str] = ""
    Settings: ClassVar[type[BaseModel]] = NoSettings
    #: Whether its candidates are evaluated with the closed-form sub-solves
    #: (:class:`rvmsim.tune.EcSolver`); the search then sets :attr:`solved`.
    solves: ClassVar[bool] = False
    #: The objective its candidates are told (:data:`rvmsim.tune.OBJECTIVES`).
    objective: ClassVar[str] = "log-score"

    def __init__(self, space: SearchSpace, *, seed: int = 0,
                 starts: Sequence[np.ndarray] = ()):
        self.space = space
        self.seed = check_seed(seed, "seed")
        #: Known good candidates (vectors of ``space``, clipped to it) the search should
        #: start from, e.g. a neighbouring design point's optimum; a strategy that cannot
        #: use them ignores them.
        self.starts: tuple[np.ndarray, ...] = ()
        self.set_starts(starts)
        #: The parameters set by the sub-solves at evaluation (those proposed are ignored):
        #: set by :func:`rvmsim.tune.solver_for` before the search starts.
        self.solved: tuple[str, ...] = ()

    def set_starts(self, starts: Sequence[np.ndarray]) -> None:
        """Set :attr:`starts` (vectors of :attr:`space`, clipped to its ranges)."""
        self.starts = tuple(np.clip(np.asarray(x, np.float64), self.space.low,
                                    self.space.high) for x in starts)

    @classmethod
    @abstractmethod
    def from_settings(cls, space: SearchSpace, settings: BaseModel, *, seed: int,
                      budget: int | None, batch: int) -> Strategy:
        """The strategy as the tuning config's section ``settings`` (an instance of
        ``Settings``) describes it; ``budget`` (``--budget``) overrides the section's size
        where given, ``batch`` is the config's batch size.  (:func:`make_strategy` sets
        :attr:`starts` afterwards.)"""

    @abstractmethod
    def batches(self) -> Batches: ...

    def total(self) -> int | None:
        """Evaluations the strategy will make, when known in advance."""
        return None


# ---------------------------------------------------------------------------- registry
#: Every strategy by name, in registration order (the built-ins: grid-random, cmaes, random).
STRATEGIES: dict[str, type[Strategy]] = {}

_T = TypeVar("_T", bound=type[Strategy])


def register_strategy(cls: _T) -> _T:
    """Class decorator: add a :class:`Strategy` subclass to :data:`STRATEGIES` under its
    ``name`` (which must be new).  Its ``section`` is a key of
    :class:`~rvmsim.search.TuningConfig` holding a ``Settings`` (the built-ins), or "" (a
    strategy without config-file settings)."""
    if not cls.name or cls.name in STRATEGIES:
        raise ValueError(f"strategy name {cls.name!r} is empty or taken")
    STRATEGIES[cls.name] = cls
    return cls


@register_strategy
class GridToRandom(Strategy):
    """The paper's grid-to-random search (see the module docstring)."""

    name = "grid-random"
    summary = "the paper's grid-to-random search"
    section = "grid_random"
    Settings = GridRandomSettings

    def __init__(self, space: SearchSpace, *, seed: int = 0, top_n: int = 2, trials: int = 20000,
                 batch: int = 1024):
        super().__init__(space, seed=seed)
        if top_n < 1 or trials < 0:
            raise ValueError("top_n must be >= 1 and trials >= 0")
        self.top_n, self.trials, self.batch = top_n, trials, batch

    @classmethod
    def from_settings(cls, space: SearchSpace, settings: BaseModel, *, seed: int,
                      budget: int | None, batch: int) -> GridToRandom:
        s = _settings(settings, GridRandomSettings)
        return cls(space, seed=seed, top_n=s.top_n, trials=s.trials if budget is None else budget,
                   batch=batch)

    def total(self) -> int:
        return self.space.grid_size() + self.top_n * self.trials

    def batches(self) -> Batches:
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


@register_strategy
class CmaEs(Strategy):
    """Bounded CMA-ES with restarts (see the module docstring).

    The first ``explore`` evaluations (default: a tenth of the budget, at most 300) are
    uniform random candidates; CMA-ES then starts from the best of them, and each restart
    from the next best explored point, so the restarts begin in different basins that are
    already known to be good."""

    name = "cmaes"
    summary = "CMA-ES"
    section = "cmaes"
    Settings: ClassVar[type[BaseModel]] = CmaesSettings

    def __init__(self, space: SearchSpace, *, seed: int = 0, budget: int = 8000,
                 sigma0: float = 0.3, popsize: int | None = None, explore: int | None = None):
        super().__init__(space, seed=seed)
        self.budget, self.sigma0, self.popsize = budget, sigma0, popsize
        self.explore = min(budget // 10, 300) if explore is None else explore

    @classmethod
    def from_settings(cls, space: SearchSpace, settings: BaseModel, *, seed: int,
                      budget: int | None, batch: int) -> CmaEs:
        s = _settings(settings, CmaesSettings)
        return cls(space, seed=seed, budget=budget or s.budget, sigma0=s.sigma0)

    def total(self) -> int:
        return self.budget

    def batches(self) -> Batches:
        return self._cma_batches()

    def _cma_batches(self, grow: float = 1.0, stagnation: bool = False) -> Batches:
        """The explore stage and the CMA-ES restarts over the parameters not in
        :attr:`solved` (those stay at their initial values); each restart's population is
        ``grow`` times the previous one's (1: the default size every time).  With
        ``stagnation``, a restart also ends when its best objective has not improved for
        ``10 + ⌈30·dim/popsize⌉`` generations (Hansen's stagnation rule)."""

        names = self.space.names
        free = np.array([i for i, n in enumerate(names) if n not in self.solved], dtype=int)
        lo, hi = self.space.low[free], self.space.high[free]
        span = hi - lo
        dim = len(free)
        full = np.array([r.init for r in self.space.ranges])

        def vector(u: np.ndarray) -> np.ndarray:
            x = full.copy()
            x[free] = lo + u * span
            return x

        rng = np.random.default_rng([self.seed, 7])
        init = (full[free] - lo) / span
        pool: list[tuple[float, int, np.ndarray]] = []  # (−objective, order, point in [0, 1])
        used = 0
        # Given starts are evaluated first, then the explored points; CMA-ES starts from the
        # best of all of them and restarts from the next best.
        given = np.array([(x[free] - lo) / span for x in self.starts]).reshape(-1, dim)
        for stage, us in (("starts", given),
                          ("explore", rng.uniform(0.0, 1.0, size=(self.explore, dim)))):
            if len(us):
                told = yield stage, [vector(u) for u in us]
                pool += [(-t[1], used + i, u) for i, (u, t) in enumerate(zip(us, told))]
                used += len(us)
        starts = [u for _, _, u in sorted(pool, key=lambda t: t[:2])] + [init]
        # Imported here, where CMA-ES starts, not at module top: the cmaes package imports
        # scipy.stats (0.3-0.5 s) for a variant we do not use, and every command that
        # tunes imports this module before its first candidate.
        from cmaes import CMA

        restart = 0
        popsize = self.popsize
        while used < self.budget:
            start = starts[restart] if restart < len(starts) else rng.uniform(0.1, 0.9, dim)
            opt = CMA(mean=np.clip(start, 0.0, 1.0), sigma=self.sigma0,
                      bounds=np.tile([0.0, 1.0], (dim, 1)), seed=_cma_seed(self.seed, restart),
                      population_size=popsize)
            patience = 10 + math.ceil(30 * dim / opt.population_size)
            best, since = -math.inf, 0
            while used < self.budget and not opt.should_stop():
                pop = [opt.ask() for _ in range(opt.population_size)]
                told = yield f"cmaes-{restart + 1}", [vector(u) for u in pop]
                used += len(pop)
                opt.tell([(u, -obj) for u, (_, obj) in zip(pop, told)])
                top = max(obj for _, obj in told)
                best, since = (top, 0) if top > best + 1e-9 else (best, since + 1)
                if stagnation and since >= patience:
                    break
            restart += 1
            if grow != 1.0:
                popsize = int(round(opt.population_size * grow))


@register_strategy
class CmaEsSolved(CmaEs):
    """CMA-ES on the parameters the closed-form sub-solves leave (see the module
    docstring): the board aspect and the guideline ECs are solved per candidate
    (:class:`rvmsim.tune.EcSolver`), CMA-ES searches the rest."""

    name = "cmaes-solved"
    summary = "CMA-ES with the guideline and board ECs solved per candidate"
    section = "cmaes_solved"
    Settings = CmaesSolvedSettings
    solves = True
    objective = "pass-first"

    def __init__(self, space: SearchSpace, *, seed: int = 0, budget: int = 8000,
                 sigma0: float = 0.3, explore: int = 100, restart_growth: float = 2.0):
        super().__init__(space, seed=seed, budget=budget, sigma0=sigma0,
                         explore=min(explore, budget))
        self.restart_growth = restart_growth

    @classmethod
    def from_settings(cls, space: SearchSpace, settings: BaseModel, *, seed: int,
                      budget: int | None, batch: int) -> CmaEsSolved:
        s = _settings(settings, CmaesSolvedSettings)
        return cls(space, seed=seed, budget=budget or s.budget, sigma0=s.sigma0,
                   explore=s.explore, restart_growth=s.restart_growth)

    def batches(self) -> Batches:
        return self._cma_batches(self.restart_growth, stagnation=True)


@register_strategy
class RandomSearch(Strategy):
    """Uniform random candidates over the ranges."""

    name = "random"
    summary = "uniform random candidates (a baseline)"
    section = "random"
    Settings = RandomSettings

    def __init__(self, space: SearchSpace, *, seed: int = 0, budget: int = 2000, batch: int = 256):
        super().__init__(space, seed=seed)
        self.budget, self.batch = budget, batch

    @classmethod
    def from_settings(cls, space: SearchSpace, settings: BaseModel, *, seed: int,
                      budget: int | None, batch: int) -> RandomSearch:
        s = _settings(settings, RandomSettings)
        return cls(space, seed=seed, budget=budget or s.budget, batch=batch)

    def total(self) -> int:
        return self.budget

    def batches(self) -> Batches:
        rng = np.random.default_rng(self.seed)
        left = self.budget
        while left > 0:
            k = min(self.batch, left)
            yield "random", list(rng.uniform(self.space.low, self.space.high,
                                             size=(k, len(self.space.ranges))))
            left -= k
