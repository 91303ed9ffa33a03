"""The ECs no ISP setting can pass at a design point (:func:`infeasible_ecs`), from each
enabled EC's feasibility reason (:attr:`EcDefinition.infeasibility
<rvmsim.criteria.EcDefinition>`, read from the fisheye labels and the scene).  Used by design
sweeps (:mod:`rvmsim.batch.feasibility`) and by ``rvmsim tune --markets`` to say why no
setting passes a market."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NotRequired, TypedDict

import numpy as np

from ..camera import FisheyeCamera
from ..errors import CriteriaError
from ..scene import Scene
from .context import SceneContext
from .measure import call_ec
from .scoring import Criteria

__all__ = ["Infeasibility", "InfeasibleDoc", "infeasible_ecs"]


class InfeasibleDoc(TypedDict):
    """An EC no ISP setting can pass (:meth:`Infeasibility.as_dict`; ``short`` is absent in
    stores made before it existed; ``market``: the market whose EC it is, in a markets
    sweep)."""

    ec: str
    reason: str
    short: NotRequired[str]
    market: NotRequired[str]


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
        found = call_ec(ec, "infeasibility", f"the fisheye labels of {scene.source}",
                        ec.infeasibility, context, criterion, criteria.options)
        if found is None:
            continue
        if not (isinstance(found, tuple) and len(found) == 2
                and all(isinstance(t, str) for t in found)):
            raise CriteriaError(ec.plugin or "<ec>", ec.id, f"the feasibility reason returned "
                                f"{found!r} (expected None or (reason, short) strings)")
        out.append(Infeasibility(ec.id, f"{ec.id}: {found[0]}", f"{ec.id}: {found[1]}"))
    return out
