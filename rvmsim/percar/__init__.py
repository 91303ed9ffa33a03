"""The per-car step of end-of-line compensation: from a car's station reading and picture to
the values written into its camera, and the station's verdict (docs/compensation.md).

Modules: :mod:`.law` (``ec-solve`` and ``reference-points``: :class:`EcSolveLaw`,
:class:`ReferencePointsLaw`, :func:`make_law`), :mod:`.picture` (what a law judges a car by:
a fisheye label image, or a true one seen with the station's errors), :mod:`.margins` (EC
margins on one scale), :mod:`.uncertainty` (the station's σ of each EC), :mod:`.conflicts`
(cars no setting can pass).
"""

from __future__ import annotations

from .conflicts import GRID_LEVELS, conflicts_on_grid, grid_of
from .factory import LAWS, check_law, make_law, nominal_draws, register_law
from .law import (STATUSES, STOP_SIGMAS, STOP_TOLERANCE, CarSolution, EcSolveLaw, PerCarLaw,
                  ReferencePointsLaw)
from .margins import FAIL_MARGIN, MarginScale
from .picture import (WARP_GRID_PX, CarPicture, EdgeWarp, GridWarp, ImagePicture,
                      SplitEvaluator, StationView, TurnWarp, body_ecs, criteria_subset)
from .uncertainty import DRAWS, StationDraws, axis_turn, ec_uncertainty, station_draws

__all__ = [
    "GRID_LEVELS", "conflicts_on_grid", "grid_of",
    "LAWS", "make_law", "nominal_draws", "register_law", "check_law",
    "CarSolution", "EcSolveLaw", "PerCarLaw", "ReferencePointsLaw", "STATUSES", "STOP_SIGMAS", "STOP_TOLERANCE",
    "FAIL_MARGIN", "MarginScale",
    "CarPicture", "EdgeWarp", "GridWarp", "ImagePicture", "SplitEvaluator", "StationView",
    "TurnWarp", "WARP_GRID_PX",
    "body_ecs", "criteria_subset",
    "DRAWS", "axis_turn", "ec_uncertainty", "station_draws", "StationDraws",
]
