"""What a search is asked to do, as frozen objects: what defines it (:class:`SearchSettings`)
and how it runs here and now (:class:`SearchOptions`).

A new option of the search is one field with one default here; the CLI, a sweep point and
a cluster task build the objects and pass them down unchanged.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..criteria import Criteria
from ..isp import IspParams
from .config import TuningConfig
from .members import OBJECTIVE_COMBINE, Aggregate
from .strategies import DEFAULT_STRATEGY, Strategy

__all__ = ["SearchSettings", "SearchOptions"]


@dataclass(frozen=True)
class SearchSettings:
    """What defines a search (the same settings and stored trials give the same search).

    Parameters
    ----------
    config : TuningConfig
        The tuned parameters, their ranges, the RVM output size and the strategies' settings.
    criteria : Criteria
    strategy : str or Strategy
        A name in :data:`rvmsim.tune.STRATEGIES` (made with :func:`rvmsim.tune.make_strategy`
        from ``config``, ``seed`` and ``budget`` on the config's space), or a strategy already
        made (its space is used; ``seed``, ``budget`` and ``starts`` are then ignored).
    seed : int
    budget : int, optional
        ``--budget`` (see :func:`rvmsim.tune.make_strategy`).
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
