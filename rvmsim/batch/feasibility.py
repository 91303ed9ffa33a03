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

from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera
from ..criteria import PATCH_SAMPLES, Criteria, PatchView, SceneContext, patch_view
from ..errors import CriteriaError
from ..scene import Scene
from .payloads import InfeasibleDoc

__all__ = ["Infeasibility", "PatchView", "patch_view", "infeasible_ecs", "PATCH_SAMPLES"]


@dataclass(frozen=True)
class Infeasibility:
    """An EC no ISP setting can pass at a design point, and why: ``reason`` is one line
    starting with the EC id (``1-1: object F's lower patch is hidden behind the bumper``),
    ``short`` a few words for a map cell (``1-1: F behind bumper``)."""

    ec: str
    reason: str
    short: str

    def as_dict(self) -> InfeasibleDoc:
        return {"ec": self.ec, "reason": self.reason, "short": self.short}


def infeasible_ecs(scene: Scene, camera: FisheyeCamera, labels: np.ndarray,
                   criteria: Criteria) -> list[Infeasibility]:
    """The enabled ECs of ``criteria`` that no ISP setting can pass at this design point:
    those whose feasibility reason (:attr:`rvmsim.criteria.EcDefinition.infeasibility`)
    gives one.

    Parameters
    ----------
    scene : Scene
        The design point's scene.
    camera : FisheyeCamera
        The camera ``labels`` was rendered with.
    labels : (H, W) uint8
        The rendered fisheye label image.
    criteria : Criteria
        The sweep's criteria (disabled or unselected ECs are never reported).

    Returns
    -------
    list of Infeasibility
        In the criteria's EC order; empty when the search has to decide.

    Raises
    ------
    CriteriaError
        An EC's feasibility reason returned something else than None or two strings.
    """
    context = SceneContext(scene, camera, np.asarray(labels))
    out = []
    for ec in criteria.ecs:
        criterion = criteria.items[ec.id]
        if ec.infeasibility is None or not criterion.enabled:
            continue
        found = ec.infeasibility(context, criterion, criteria.options)
        if found is None:
            continue
        if not (isinstance(found, tuple) and len(found) == 2
                and all(isinstance(t, str) for t in found)):
            raise CriteriaError(ec.plugin or "<ec>", ec.id, f"the feasibility reason returned "
                                f"{found!r} (expected None or (reason, short) strings)")
        out.append(Infeasibility(ec.id, f"{ec.id}: {found[0]}", f"{ec.id}: {found[1]}"))
    return out
