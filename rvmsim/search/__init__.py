"""What a tuning run searches and how: the search space, the strategies (one registry) and
the tuning config that sets them up.

- :mod:`.space`: :class:`ParamRange`, :class:`SearchSpace`, :func:`default_space`.
- :mod:`.strategies`: :class:`Strategy`, the built-ins (grid-random, CMA-ES, CMA-ES with
  closed-form sub-solves, random), :data:`STRATEGIES`, :func:`register_strategy`.
- :mod:`.config`: the tuning config file (:class:`TuningConfig`, :func:`load_tuning_config`)
  and the strategy it describes (:func:`make_strategy`).

They stand below :mod:`rvmsim.runs` (a run records its config and search space) and
:mod:`rvmsim.tune` (which runs the search); :mod:`rvmsim.tune` exports them too, as its
search API.
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
    DiverseConfig,
    load_tuning_config,
    make_strategy,
)

__all__ = [
    "ParamRange",
    "SearchSpace",
    "default_space",
    "Strategy",
    "GridToRandom",
    "CmaEs",
    "CmaEsSolved",
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
    "DiverseConfig",
    "load_tuning_config",
    "make_strategy",
]
