"""Which required-visible areas of the test objects the guidelines cover on the RVM image.

Required areas, as the markets' ECs read them (docs/markets.md): FMVSS 111 — each of A–E
whole (S5.5.1(b)), and F and G (their lower 150 mm stripe patch and the stripe); UN R158 — the
row-1 cylinders' top band and top, the row-2 and row-3 cylinders whole.  The guidelines may
be drawn over the field of vision (R158 allows reversing information there); this says which
of these areas they cover, and how much of each one's shown pixels.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import cv2
import numpy as np

from .. import labels as L
from ..isp import IspMap, apply_map, build_map
from ..render import cached_render
from ..scene import Scene, site_scene
from .overlay import GuidelineSet
from .project import DisplayLine

__all__ = ["line_mask", "required_areas", "required_coverage", "covered_by"]


def line_mask(gset: GuidelineSet, lines: Sequence[DisplayLine]) -> np.ndarray:
    """(H, W) bool: the RVM pixels ``lines`` are drawn over (at the spec's width)."""
    out = gset.view.output
    mask = np.zeros((out.height, out.width), np.uint8)
    thick = max(1, int(round(gset.spec.line_width_px)))
    for line in lines:
        for piece in line.pieces:
            pts = np.round(piece.uv_px * 16).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(mask, [pts], False, 255, thick, cv2.LINE_8, shift=4)
    return mask > 0


def required_areas(scene: Scene) -> dict[str, tuple[int, ...]]:
    """Per object of ``scene``'s site, the labels of its required-visible area."""
    areas: dict[str, tuple[int, ...]] = {}
    if scene.test_site.site_objects:
        for obj in scene.test_site.site_objects:
            body, band, top = L.site_object_labels(obj.index)
            areas[obj.name] = (band, top) if obj.row == "row1" else (body, band, top)
    elif scene.test_site.fmvss:
        for letter in L.OBJECT_LETTERS:
            ids = (L.object_body(letter), L.object_stripe(letter))
            if letter in ("F", "G"):
                ids = (L.object_stripe(letter), L.object_patch(letter))
            areas[letter] = ids
    return areas


def _covered(scene: Scene, gset: GuidelineSet, fisheye_labels: np.ndarray, isp_map: IspMap
             ) -> dict[str, dict[str, Any]]:
    """Per required area the lines are drawn over: its shown px, and the px the static lines
    and each steering angle's trajectories cover (only angles that cover some)."""
    rvm = apply_map(fisheye_labels, isp_map, labels=True)
    areas = required_areas(scene)
    lut = np.full(256, -1, np.int64)
    names = list(areas)
    for k, ids in enumerate(areas.values()):
        lut[list(ids)] = k
    area_of = lut[rvm]
    shown = np.bincount(area_of[area_of >= 0], minlength=len(names))

    def hits(lines: Sequence[DisplayLine]) -> np.ndarray:
        under = area_of[line_mask(gset, lines)]
        return np.bincount(under[under >= 0], minlength=len(names))

    static = hits(gset.static)
    per_angle = [(a, hits(group)) for a, group in zip(gset.steering_deg, gset.trajectories)]
    out: dict[str, dict[str, Any]] = {}
    for k, name in enumerate(names):
        angles = {a: int(h[k]) for a, h in per_angle if h[k]}
        if static[k] or angles:
            worst = max([int(static[k]), *angles.values()])
            out[name] = {"shown_px": int(shown[k]), "static_px": int(static[k]),
                         "trajectory_px": {f"{a:g}": v for a, v in angles.items()},
                         "fraction": worst / max(int(shown[k]), 1)}
    return out


def required_coverage(scene: Scene, gset: GuidelineSet, fisheye_labels: np.ndarray, *,
                      isp_map: IspMap | None = None, progress: bool = False
                      ) -> dict[str, Any]:
    """The required areas the lines cover: ``{"fmvss111": {...}, "unr158": {...}}``; per
    covered object its shown px, the px the static lines cover, per steering angle the px
    its trajectories cover, and ``fraction``: the largest of these over the shown px.

    ``fisheye_labels``: the scene's own render (its FMVSS site); the UN R158 site is
    rendered (or read from the render cache).  ``isp_map``: the setting's map
    (:func:`rvmsim.isp.build_map` for the fisheye size and ``gset.view.output``), when the
    caller has it already; one map serves both sites (one camera).
    """
    r158 = site_scene(scene, "unr158")
    r158_labels = cached_render(r158, progress=progress)[0].labels
    if isp_map is None:
        h, w = fisheye_labels.shape
        isp_map = build_map(gset.view.params, (w, h), gset.view.output)
    return {"fmvss111": _covered(scene, gset, fisheye_labels, isp_map),
            "unr158": _covered(r158, gset, r158_labels, isp_map)}


def covered_by(area: Mapping[str, Any]) -> str:
    """Which lines cover one required area of :func:`required_coverage`'s result, in words
    (``"static lines, trajectories at 12 steering angles"``)."""
    by = (["static lines"] if area["static_px"] else []) + (
        [f"trajectories at {len(area['trajectory_px'])} steering angles"]
        if area["trajectory_px"] else [])
    return ", ".join(by)
