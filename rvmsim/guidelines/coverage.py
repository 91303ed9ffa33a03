"""Which required-visible areas of the test objects the guidelines cover on the RVM image.

Required areas, as the markets' ECs read them (docs/markets.md): FMVSS 111 — each of A–E
whole (S5.5.1(b)), and F and G (their lower 150 mm stripe patch and the stripe); UN R158 — the
row-1 cylinders' top band and top, the row-2 and row-3 cylinders whole.  The guidelines may
be drawn over the field of vision (R158 allows reversing information there); this says which
of these areas they cover, and how much of each one's shown pixels.
"""

from __future__ import annotations

from typing import Any

import cv2
import numpy as np

from .. import labels as L
from ..isp import apply_map, build_map_exact
from ..render import cached_render
from ..scene import Scene, site_scene
from .overlay import GuidelineSet

__all__ = ["line_mask", "required_areas", "required_coverage"]


def line_mask(gset: GuidelineSet) -> np.ndarray:
    """(H, W) bool: the RVM pixels any of the set's lines (every angle) is drawn over."""
    out = gset.view.output
    mask = np.zeros((out.height, out.width), np.uint8)
    thick = max(1, int(round(gset.spec.line_width_px)))
    for line in gset.lines():
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


def _covered(scene: Scene, gset: GuidelineSet, fisheye_labels: np.ndarray, mask: np.ndarray
             ) -> dict[str, dict[str, float]]:
    cam = scene.fisheye_camera()
    isp_map = build_map_exact(gset.view.params, (cam.width, cam.height), gset.view.output)
    rvm = apply_map(fisheye_labels, isp_map, labels=True)
    counts = np.bincount(rvm.ravel(), minlength=256)
    under = np.bincount(rvm[mask], minlength=256)
    out = {}
    for name, ids in required_areas(scene).items():
        seen, hit = int(counts[list(ids)].sum()), int(under[list(ids)].sum())
        if hit:
            out[name] = {"covered_px": hit, "shown_px": seen, "fraction": hit / seen}
    return out


def required_coverage(scene: Scene, gset: GuidelineSet, fisheye_labels: np.ndarray, *,
                      progress: bool = False) -> dict[str, Any]:
    """The required areas the lines cover: ``{"fmvss111": {...}, "unr158": {...}}``, per
    object its covered and shown px and the covered fraction (only objects covered).

    ``fisheye_labels``: the scene's own render (its FMVSS site); the UN R158 site is
    rendered (or read from the render cache).
    """
    mask = line_mask(gset)
    r158 = site_scene(scene, "unr158")
    r158_labels = cached_render(r158, progress=progress)[0].labels
    return {"fmvss111": _covered(scene, gset, fisheye_labels, mask),
            "unr158": _covered(r158, gset, r158_labels, mask)}
