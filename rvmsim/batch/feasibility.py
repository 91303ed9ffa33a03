"""Search-free infeasibility: the ECs no ISP setting can pass at a design point.

The ISP only resamples the fisheye image (:mod:`rvmsim.isp`): every label the RVM image
shows is a label of the fisheye image, and anything cut off by the sensor border or the
lens's image circle, or hidden behind the car body, stays cut off or hidden whatever the
parameters.  So some failures need no search to prove.  Which, is each EC's own business:
an EC definition may carry a feasibility reason
(:attr:`EcDefinition.infeasibility <rvmsim.criteria.EcDefinition>`, read from the fisheye
labels and the scene); :func:`infeasible_ecs` asks every enabled EC of the criteria that
has one.  The paper's ECs' reasons (the lower patches of F and G out of view, cut off or
hidden; the measured labels absent from the fisheye image) are in
:mod:`rvmsim.criteria.feasibility`, with :func:`~rvmsim.criteria.patch_view`.
"""

from __future__ import annotations

from ..criteria import PATCH_SAMPLES, PatchView, patch_view
from ..criteria.infeasible import Infeasibility, infeasible_ecs

__all__ = ["Infeasibility", "PatchView", "patch_view", "infeasible_ecs", "PATCH_SAMPLES"]
