"""Which ECs a scene can support at all: an EC whose measured objects the scene's own
settings leave out (a test object, the guidelines or the board disabled, no vehicle) cannot
be measured whatever the ISP does, so scoring it only reports "—" and 0.

Read from the scene's settings alone (nothing rendered), so commands check it before any
work (:func:`check_supported`); whether the objects the scene *has* are in view is the
render-time question of :mod:`rvmsim.criteria.infeasible`.  What an EC needs is its
:attr:`~rvmsim.criteria.EcDefinition.needs` (or the labels of its
:class:`~rvmsim.criteria.LabelsAbsent` feasibility reason).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .. import labels as L
from ..errors import RvmsimError
from ..scene import Scene
from .feasibility import LabelsAbsent
from .registry import EcDefinition
from .scoring import Criteria

__all__ = ["Unsupported", "ec_needs", "label_left_out", "unsupported_ecs", "check_supported",
           "supported_criteria", "ONLY_SUPPORTED_HINT"]

#: What a refusal suggests (the commands' opt-in flag).
ONLY_SUPPORTED_HINT = "add --only-supported to score only the ECs it supports"


@dataclass(frozen=True)
class Unsupported:
    """An enabled EC a scene cannot support: ``keys`` the scene settings that leave its
    measured objects out (``test_site.board.enabled: false``)."""

    ec: str
    keys: tuple[str, ...]


def ec_needs(ec: EcDefinition) -> tuple[tuple[int, ...], ...]:
    """The label sets ``ec`` needs (:attr:`EcDefinition.needs`, else its
    :class:`LabelsAbsent` reason's labels, else none)."""
    if ec.needs:
        return ec.needs
    if isinstance(ec.infeasibility, LabelsAbsent):
        return (tuple(ec.infeasibility.labels),)
    return ()


def _object_letter(label: int) -> str | None:
    for letter in L.OBJECT_LETTERS:
        ids = {L.object_body(letter), L.object_stripe(letter)}
        if letter in "FG":
            ids.add(L.object_patch(letter))
        if label in ids:
            return letter
    return None


def label_left_out(scene: Scene, label: int) -> str | None:
    """The scene setting that leaves ``label`` out of every image of it
    (``test_site.objects.F.enabled: false``), or None when the scene may show it (or the
    label is not one the scene's settings switch)."""
    site = scene.test_site
    letter = _object_letter(label)
    guide = label in (L.GUIDE_SIDE_NEG_X, L.GUIDE_SIDE_POS_X) or \
        L.guide_cross(1) <= label < L.guide_cross(1) + L.MAX_CROSS_LINES
    if (letter is not None or guide) and not site.fmvss:
        return "test_site.fmvss: false"
    if letter is not None:
        return None if site.object_centre(letter) is not None else \
            f"test_site.objects.{letter}.enabled: false"
    if guide:
        if not site.guidelines.enabled:
            return "test_site.guidelines.enabled: false"
        line = label - L.guide_cross(1) + 1
        if line > len(site.guidelines.cross_z) and label >= L.guide_cross(1):
            n = len(site.guidelines.cross_z)
            return f"test_site.guidelines.cross_z: {n} line{'s' if n != 1 else ''}, no line {line}"
        return None
    if label == L.BOARD and not site.board.enabled:
        return "test_site.board.enabled: false"
    if label in (L.BUMPER, L.GARNISH, L.TRUNK) and scene.vehicle is None:
        return "vehicle: none"
    return None


def unsupported_ecs(scene: Scene, criteria: Criteria) -> list[Unsupported]:
    """The enabled ECs of ``criteria`` that ``scene`` cannot support: one of the label sets
    the EC needs (:func:`ec_needs`) is wholly left out by the scene's settings."""
    out = []
    for ec in criteria.ecs:
        if not criteria.items[ec.id].enabled:
            continue
        keys: list[str] = []
        for ids in ec_needs(ec):
            why = [label_left_out(scene, i) for i in ids]
            if ids and all(why):
                keys.extend(k for k in dict.fromkeys(why) if k and k not in keys)
        if keys:
            out.append(Unsupported(ec.id, tuple(keys)))
    return out


def _grouped(items: list[Unsupported]) -> str:
    """``1-1, 1-2 (test_site.objects.F.enabled: false); 4-1 (test_site.board.enabled:
    false)``: the ECs grouped by the settings that leave them out."""
    groups: dict[tuple[str, ...], list[str]] = {}
    for u in items:
        groups.setdefault(u.keys, []).append(u.ec)
    return "; ".join(f"{', '.join(ecs)} ({', '.join(keys)})" for keys, ecs in groups.items())


def check_supported(scene: Scene, criteria: Criteria, scene_file: object = None, *,
                    only_supported: bool = False) -> Criteria:
    """``criteria`` when ``scene`` supports every enabled EC; with ``only_supported`` the
    criteria with the ones it cannot support disabled (:func:`supported_criteria`).

    Raises
    ------
    RvmsimError
        One line naming the scene file, the ECs and the settings that leave them out (or,
        with ``only_supported``, saying that the scene supports none).
    """
    missing = unsupported_ecs(scene, criteria)
    if not missing:
        return criteria
    name = scene_file if scene_file is not None else scene.source
    enabled = [ec for ec in criteria.ids if criteria.items[ec].enabled]
    if only_supported and len(missing) < len(enabled):
        return supported_criteria(criteria, missing)
    if only_supported:
        raise RvmsimError(f"{name}: supports none of the criteria's ECs: {_grouped(missing)}; "
                          "enable those objects in the scene")
    raise RvmsimError(f"{name}: cannot support EC {_grouped(missing)}: their objects are left "
                      f"out of the scene; enable them, disable those ECs in a criteria file, "
                      f"or {ONLY_SUPPORTED_HINT}")


def supported_criteria(criteria: Criteria, missing: list[Unsupported]) -> Criteria:
    """``criteria`` with the ECs of ``missing`` disabled (not scored, not in the pass
    verdict), as a criteria file's ``ID: {enabled: false}`` does."""
    off = {u.ec for u in missing}
    items = {k: dataclasses.replace(c, enabled=False) if k in off else c
             for k, c in criteria.items.items()}
    return dataclasses.replace(criteria, items=items)
