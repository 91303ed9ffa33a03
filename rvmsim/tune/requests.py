"""What a search or a tuning run is asked to do, as frozen objects: what defines it
(:class:`SearchSettings`, :class:`TuneRequest`) and how it runs here and now
(:class:`SearchOptions`, :class:`RunOptions`).

A new option of the search is one field with one default here; the CLI, a sweep point and
a cluster task build the objects and pass them down unchanged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Union

from ..criteria import Criteria
from ..isp import IspParams
from ..search.config import TuningConfig
from ..markets import parse_markets
from .members import OBJECTIVE_COMBINE, Aggregate, parse_aggregate
from .robust import DEFAULT_SAMPLES, ROBUST_AGGREGATE, check_samples
from ..search.strategies import DEFAULT_STRATEGY, Strategy

if TYPE_CHECKING:
    from ..compensation import CompensationModel
    from ..scene import Scene

__all__ = ["SearchSettings", "SearchOptions", "TuneRequest", "RunOptions", "SceneArg", "Shared",
           "Robust", "Markets", "RunKindRequest"]

#: A scene as a tuning run takes it: its file, or a loaded Scene.
SceneArg = Union[str, Path, "Scene"]


@dataclass(frozen=True)
class SearchSettings:
    """What defines a search (the same settings and stored trials give the same search).

    Parameters
    ----------
    config : TuningConfig
        The tuned parameters, their ranges, the RVM output size and the strategies' settings.
    criteria : Criteria
    strategy : str or Strategy
        A name in :data:`rvmsim.search.STRATEGIES` (made with :func:`rvmsim.search.make_strategy`
        from ``config``, ``seed`` and ``budget`` on the config's space), or a strategy already
        made (its space is used; ``seed``, ``budget`` and ``starts`` are then ignored).
    seed : int
    budget : int, optional
        ``--budget`` (see :func:`rvmsim.search.make_strategy`).
    starts : tuple of IspParams
        Parameter sets to start from (e.g. neighbouring design points' optima), evaluated
        first by the strategies that use them (:attr:`Strategy.starts`).
    aggregate : str or Aggregate
        Several members: how their EC scores combine, ``min`` or ``quantile Q``
        (:func:`rvmsim.tune.parse_aggregate`).
    solve : str
        Several members: how the sub-solves of ``cmaes-solved`` combine
        (:data:`rvmsim.tune.SOLVE_MODES`).
    combine : str
        Several members: how the ``min`` aggregate combines the members' objectives
        (:data:`rvmsim.tune.OBJECTIVE_COMBINE`: ``sum-violation`` or ``min``).
    compensation : CompensationModel, optional
        Several members: judge each member that carries a station reading
        (:attr:`rvmsim.tune.Member.measured`) with its per-car values
        (:mod:`rvmsim.tune.compensated`).
    """

    config: TuningConfig
    criteria: Criteria
    strategy: str | Strategy = DEFAULT_STRATEGY
    seed: int = 0
    budget: int | None = None
    starts: tuple[IspParams, ...] = ()
    aggregate: str | Aggregate = "min"
    solve: str = "mean"
    combine: str = OBJECTIVE_COMBINE
    compensation: CompensationModel | None = None


@dataclass(frozen=True)
class SearchOptions:
    """How a search runs here (not part of what it finds, except where it stops).

    Parameters
    ----------
    workers : int
        Worker processes (1: evaluate in this process).
    max_time : float, optional
        Stop (resumably) after the batch during which this many seconds have passed.
    target_score : float, optional
        Stop once the best EC score reaches this.
    on_batch : callable, optional
        Called with (trials done, best EC score, stage) after every batch (progress bars).
    """

    workers: int = 1
    max_time: float | None = None
    target_score: float | None = None
    on_batch: Callable[[int, float, str], None] | None = None


@dataclass(frozen=True)
class TuneRequest:
    """What defines a new tuning run (:func:`rvmsim.tune.tune`); recorded in its store as
    :class:`~rvmsim.tune.RunSettings`, so a resumed run reads it back.

    Parameters
    ----------
    scenes : tuple of (path or Scene)
        The scene file, or a loaded :class:`~rvmsim.scene.Scene` (recorded by
        ``scene_file``, by default its ``source``); two or more make a shared run (one
        parameter set for all; the space is fitted to the first scene's camera, and every
        scene's camera must have its sensor size).  One scene may be given alone.
    strategy : str
        A name in :data:`rvmsim.search.STRATEGIES`.
    config : TuningConfig, optional
        Default: ``TuningConfig()`` (ranges fitted to the camera).
    criteria : Criteria, optional
        Default: loaded from ``criteria_file``, default the paper's.
    criteria_file : path, optional
        Recorded, for ``--resume`` and the report.
    seed : int
    budget : int, optional
        Evaluations for ``cmaes-solved``/``cmaes``/``random``; for ``grid-random`` the fine
        trials per seed (T), replacing the config's value (a shortened protocol).
    kind : Shared, Robust or Markets, optional
        What kind of run, with its own settings: :class:`Shared` (how several scenes'
        scores combine), :class:`Robust` (judged over mount and load variation samples,
        optionally after end-of-line compensation) or :class:`Markets` (one setting for
        several markets).  Default: one scene on its own image, or several scenes as
        ``Shared()``.
    scene_file : path, optional
        The path recorded for a loaded Scene given alone.
    only_supported : bool
        Tune only the ECs the scenes support (``--only-supported``): those whose measured
        objects a scene leaves out (:func:`rvmsim.criteria.unsupported_ecs`) are disabled
        and recorded; without it such a scene is refused before any work.
    """

    scenes: tuple[SceneArg, ...]
    strategy: str = DEFAULT_STRATEGY
    config: TuningConfig | None = None
    criteria: Criteria | None = None
    criteria_file: str | Path | None = None
    seed: int = 0
    budget: int | None = None
    kind: RunKindRequest | None = None
    scene_file: str | Path | None = None
    only_supported: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.scenes, (tuple, list)) or not self.scenes:
            raise TypeError("TuneRequest.scenes: give a tuple of one or more scenes")
        object.__setattr__(self, "scenes", tuple(self.scenes))
        if self.kind is not None and not isinstance(self.kind, (Shared, Robust, Markets)):
            raise TypeError(f"TuneRequest.kind: {self.kind!r} is not Shared, Robust or Markets")

    @property
    def shared(self) -> bool:
        """Several scenes: one parameter set for all."""
        return len(self.scenes) > 1


@dataclass(frozen=True)
class Shared:
    """One parameter set for several scenes (``rvmsim tune --shared``): a member per
    scene, passing where every scene passes (:mod:`rvmsim.tune.shared`).

    Parameters
    ----------
    aggregate : str
        How the scenes' EC scores combine: ``min`` or ``quantile Q``
        (:func:`rvmsim.tune.parse_aggregate`).
    """

    aggregate: str = "min"

    def __post_init__(self) -> None:
        object.__setattr__(self, "aggregate", parse_aggregate(self.aggregate).text)


@dataclass(frozen=True)
class Robust:
    """A run judged over production variation (``rvmsim tune --robust``,
    :mod:`rvmsim.tune.robust`): every candidate on each scene's nominal image and
    ``samples`` mount and load samples of it; one scene or several (then shared).

    Parameters
    ----------
    samples : int
        Variation samples per scene (``--samples K``), 1 to
        :data:`rvmsim.tune.robust.MAX_SAMPLES`.
    variation_file : path, optional
        The variation to draw them from (``--variation``; default: each scene's
        ``variation`` section).
    compensation : CompensationModel, optional
        Tune for the yield after end-of-line compensation: each sample judged with the
        per-car values a station writes for it (``--compensation``,
        :mod:`rvmsim.tune.compensated`).
    aggregate : str
        How the members' EC scores combine (default
        :data:`rvmsim.tune.robust.ROBUST_AGGREGATE`).
    """

    samples: int = DEFAULT_SAMPLES
    variation_file: str | Path | None = None
    compensation: CompensationModel | None = None
    aggregate: str = ROBUST_AGGREGATE

    def __post_init__(self) -> None:
        check_samples(self.samples)
        object.__setattr__(self, "aggregate", parse_aggregate(self.aggregate).text)


@dataclass(frozen=True)
class Markets:
    """One setting for several markets (``rvmsim tune --markets fmvss111-full,unr158``,
    :mod:`rvmsim.markets`): each scene at each market's site, judged with the market's
    criteria (so the request gives no criteria); passes where every pair passes.

    Parameters
    ----------
    markets : str or sequence of str
        The markets (:func:`rvmsim.markets.parse_markets`): comma-separated, or a list.
    aggregate : str
        How the (scene, market) pairs' EC scores combine.
    """

    markets: str | tuple[str, ...]
    aggregate: str = "min"

    def __post_init__(self) -> None:
        parse_markets(self.markets)  # a market this version does not know: refused now
        object.__setattr__(self, "aggregate", parse_aggregate(self.aggregate).text)


#: What :attr:`TuneRequest.kind` takes.
RunKindRequest = Union[Shared, Robust, Markets]


@dataclass(frozen=True)
class RunOptions:
    """How a tuning run runs here (not recorded: a resume may use others).

    Parameters
    ----------
    workers : int
        Worker processes (1: evaluate in this process).
    max_time : float, optional
        Stop (resumably) after this many seconds.
    target_score : float, optional
        Stop once the best EC score reaches this.
    progress : bool
        Show a progress bar (evaluations/s, best EC score, ETA).
    progress_position : int
        Line of that bar (``rvmsim batch`` puts its overall bar above it).
    """

    workers: int = 1
    max_time: float | None = None
    target_score: float | None = None
    progress: bool = False
    progress_position: int = 0
