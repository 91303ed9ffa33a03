"""Measurements on the test objects of a site definition (UN R158's rows, JNCAP's poles):
which part of each cylinder's surface the RVM image shows, and why a part can never show.

Written against the public API (:class:`~rvmsim.criteria.SceneContext`,
:class:`~rvmsim.criteria.IspView`), like :mod:`.objects`, for the plugins
:mod:`rvmsim.regulations.unr158.ecs` and :mod:`rvmsim.regulations.jp.ecs`.

A cylinder's side is sampled on a grid of ``step_m`` (arc length × height, cell centres)
and its top face on rings ``step_m`` apart.  Per scene (once, :meth:`SceneContext.shared`),
each sample is *seen* when its surface faces the camera, it projects into the lens's field
and onto the sensor, and the rendered label image shows the object at its pixel (nothing in
front of it but, possibly, another of the site's objects: each object is judged as if it
stood alone, :func:`rvmsim.regulations.objects.standing_alone_labels`).  Per candidate it is *shown* when it is seen and its pixel lies
inside the RVM image's footprint.  A row-1 cylinder of R158 passes when a square of
``area_m`` × ``area_m`` of its side is wholly shown, or its whole top face
(:func:`shown_area`).

Convention
----------
Scene frame of :mod:`rvmsim.camera` (y toward the ground; a cylinder stands on y = 0),
fisheye pixel centres at integer coordinates; azimuth 0 faces +z (away from the car).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .. import labels as L
from ..scene import SiteObject
from ..criteria.context import SceneContext
from ..criteria.measure import LabelSource
from .objects import silhouette, standing_alone_labels

__all__ = ["SAMPLE_STEP_M", "row_objects", "SurfaceView", "surface_view", "ShownArea",
           "shown_area", "largest_square_cells", "hidden_reason"]

#: What shows behind an object's outline (not in front of it).
_BACKGROUND = (L.GROUND, L.SKY, L.GROUND_PATTERN)

#: Spacing of the surface samples, metres (a row-1 cylinder ~1 m from the camera: ~4 fisheye
#: px per step at 390 px/rad).
SAMPLE_STEP_M = 0.01


def row_objects(ctx: SceneContext, row: str) -> list[SiteObject]:
    """The objects of the scene's site in row ``row`` (empty at another site)."""
    return [o for o in ctx.scene.test_site.site_objects if o.row == row]


@dataclass(frozen=True)
class SurfaceView:
    """How the camera sees one cylinder's surface (per scene).

    ``side_px`` (nh, na, 2) int32 fisheye px of the side samples (rows: heights from the
    ground up, columns: azimuth); ``side_seen`` (nh, na) bool; ``top_px`` (m, 2) int32 and
    ``top_seen`` (m,) bool for the top face; ``box`` (x0, y0, x1, y1) fisheye px bounding
    every seen sample (exclusive ends; None when none is seen); ``step_m`` the spacing;
    ``max_square`` the largest all-seen square of the side, cells (what the whole fisheye
    image shows: no candidate shows more).
    """

    side_px: np.ndarray
    side_seen: np.ndarray
    top_px: np.ndarray
    top_seen: np.ndarray
    box: tuple[int, int, int, int] | None
    step_m: float
    max_square: int = 0


def _seen(ctx: SceneContext, pts: np.ndarray, normals: np.ndarray, own: tuple[int, ...]
          ) -> tuple[np.ndarray, np.ndarray]:
    """(N, 2) int32 px and (N,) bool seen of scene points with outward normals.

    A facing sample on the sensor is seen where its pixel shows the object; also where it
    shows the background (ground, sky) next to a pixel that shows the object: the sample
    lies within a pixel of the object's outline (a grazing limb, the rim of the top face),
    where rounding and not anything in front of it decides the pixel."""
    cam = ctx.camera
    labels = ctx.fisheye_labels
    facing = np.einsum("ij,ij->i", normals, cam.position[None, :] - pts) > 0
    uv, in_fov = cam.project(pts)
    px = np.round(np.nan_to_num(uv, nan=-1e6)).astype(np.int64)
    on = (in_fov & (px[:, 0] >= 0) & (px[:, 0] < cam.width) & (px[:, 1] >= 0)
          & (px[:, 1] < cam.height))
    lab = np.zeros(len(pts), np.uint8)
    lab[on] = labels[px[on, 1], px[on, 0]]
    mine = np.isin(lab, own)
    edge = np.flatnonzero(facing & on & ~mine & np.isin(lab, _BACKGROUND))
    if len(edge):
        near = np.zeros(len(edge), bool)
        for du in (-1, 0, 1):
            for dv in (-1, 0, 1):
                u = np.clip(px[edge, 0] + du, 0, cam.width - 1)
                v = np.clip(px[edge, 1] + dv, 0, cam.height - 1)
                near |= np.isin(labels[v, u], own)
        mine[edge] = near
    seen = facing & on & mine
    return np.clip(px, -2**30, 2**30).astype(np.int32), seen


def _compute_view(ctx: SceneContext, name: str, step: float) -> SurfaceView | None:
    obj = next((o for o in ctx.scene.test_site.site_objects if o.name == name), None)
    if obj is None:
        return None
    own = standing_alone_labels(ctx.scene, name)
    r, h = obj.radius, obj.height
    na = max(8, int(round(2 * math.pi * r / step)))
    nh = max(2, int(round(h / step)))
    az = (np.arange(na) + 0.5) * 2 * math.pi / na
    y = (np.arange(nh) + 0.5) * h / nh
    A, Y = np.meshgrid(az, y)
    nrm = np.stack([np.sin(A), np.zeros_like(A), np.cos(A)], -1).reshape(-1, 3)
    pts = np.stack([obj.x + r * np.sin(A), -Y, obj.z + r * np.cos(A)], -1).reshape(-1, 3)
    side_px, side_seen = _seen(ctx, pts, nrm, own)
    rings = [((k + 0.5) * step, max(6, int(round(2 * math.pi * (k + 0.5) * step / step))))
             for k in range(max(1, int(r / step)))]
    top = np.array([[obj.x + rho * math.sin(t), -h, obj.z + rho * math.cos(t)]
                    for rho, n in rings for t in (np.arange(n) + 0.5) * 2 * math.pi / n])
    top_px, top_seen = _seen(ctx, top, np.tile([0.0, -1.0, 0.0], (len(top), 1)), own)
    seen_px = np.concatenate([side_px[side_seen], top_px[top_seen]])
    box = None
    if len(seen_px):
        lo, hi = seen_px.min(axis=0), seen_px.max(axis=0) + 1
        box = (int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1]))
    seen = side_seen.reshape(nh, na)
    return SurfaceView(side_px.reshape(nh, na, 2), seen, top_px, top_seen, box, step,
                       largest_square_cells(seen))


def surface_view(ctx: SceneContext, name: str, step_m: float = SAMPLE_STEP_M
                 ) -> SurfaceView | None:
    """Object ``name``'s surface samples as the camera sees them (once per scene; None when
    the scene's site has no such object)."""
    return ctx.shared(("site.surface", name, step_m), lambda: _compute_view(ctx, name, step_m))


def largest_square_cells(mask: np.ndarray, wrap_columns: bool = True,
                         at_most: int | None = None) -> int:
    """Side, in cells, of the largest all-true square of ``mask`` (rows × columns), its
    columns wrapping around (a cylinder's azimuth) when ``wrap_columns``; ``at_most``: a
    known upper bound (tried first)."""

    if not mask.any():
        return 0
    m = mask.astype(np.uint8)
    rows, cols = m.shape
    if wrap_columns:
        m = np.concatenate([m, m[:, : min(cols, rows)]], axis=1)

    def fits(k: int) -> bool:
        return bool(cv2.erode(m, np.ones((k, k), np.uint8), borderType=cv2.BORDER_CONSTANT,
                              borderValue=0).any())

    lo, hi = 1, min(rows, cols) if at_most is None else max(1, min(rows, cols, at_most))
    if hi > 1 and fits(hi):
        return hi
    hi -= 1
    while lo < hi:  # the largest k with a k × k square all true
        k = (lo + hi + 1) // 2
        if fits(k):
            lo = k
        else:
            hi = k - 1
    return lo


@dataclass(frozen=True)
class ShownArea:
    """What the RVM image shows of one cylinder: the side of the largest wholly shown
    square of its side surface (``square_m``, metres) and the shown fraction of its top face
    (``top_fraction``, 0–1)."""

    square_m: float
    top_fraction: float

    def margin(self, area_m: float, top: bool = True) -> float:
        """max(square / area, top fraction): ≥ 1 when a square of ``area_m`` or (``top``)
        the whole top is shown; square / area alone without ``top``."""
        return max(self.square_m / area_m, self.top_fraction if top else 0.0)


def _shown(view: SurfaceView, poly: np.ndarray | None) -> tuple[np.ndarray, np.ndarray] | None:
    """Which seen side and top samples lie inside the footprint polygon; None when every
    seen sample does (no polygon, or the polygon holds the samples' whole box)."""

    if poly is None or view.box is None:
        return None
    x0, y0, x1, y1 = view.box
    inside = np.zeros((y1 - y0, x1 - x0), np.uint8)
    pts = np.round((poly - (x0, y0)) * 16.0).astype(np.int32).reshape(-1, 1, 2)
    cv2.fillPoly(inside, [pts], 255, cv2.LINE_8, shift=4)
    if cv2.countNonZero(inside) == inside.size:
        return None  # the RVM border is nowhere near the object

    def look(px: np.ndarray, seen: np.ndarray) -> np.ndarray:
        out = np.zeros(seen.shape, bool)
        at = px[seen]  # seen samples lie inside the box by its construction
        out[seen] = inside[at[:, 1] - y0, at[:, 0] - x0] > 0
        return out

    return look(view.side_px, view.side_seen), look(view.top_px, view.top_seen)


def shown_area(src: LabelSource, name: str, *, bound: bool = False) -> ShownArea | None:
    """What the candidate's RVM image shows of object ``name`` (None: no such object, or no
    scene or map).  ``bound``: what the whole fisheye image shows (an upper bound for any
    candidate: the feasibility reason)."""
    ctx = src.context
    if ctx is None or (src.isp is None and not bound):
        return None
    view = surface_view(ctx, name)
    if view is None:
        return None
    isp = src.isp
    poly = None if bound or isp is None else src.shared(("footprint", 32),
                                                        lambda: isp.footprint(32))
    shown = _shown(view, poly)
    if shown is None:  # everything the fisheye shows of it, the RVM image shows
        return ShownArea(view.max_square * view.step_m,
                         float(view.top_seen.mean()) if len(view.top_seen) else 0.0)
    side, top = shown
    return ShownArea(largest_square_cells(side, at_most=view.max_square) * view.step_m,
                     float(top.mean()) if len(top) else 0.0)


def hidden_reason(ctx: SceneContext, name: str) -> str | None:
    """Why part of object ``name``'s silhouette can never show: a phrase after its name
    ("is partly hidden behind the bumper", "is cut by the sensor border", …) from the
    fisheye labels over its hidden pixels; None when the whole silhouette shows."""

    sil = silhouette(ctx, name)
    if sil is None:
        return "is not in the lens's field of view"
    if sil.visible_area >= sil.area:
        return None
    hidden = cv2.bitwise_and(sil.inner, cv2.bitwise_not(sil.visible)) > 0
    x0, y0 = sil.box
    h, w = hidden.shape
    labels = ctx.fisheye_labels
    vv, uu = np.nonzero(hidden)
    u, v = uu + x0, vv + y0
    off = (u < 0) | (v < 0) | (u >= labels.shape[1]) | (v >= labels.shape[0])
    lab = labels[v[~off], u[~off]]
    names = L.label_names()
    counts: dict[str, int] = {}
    if off.any():
        counts["the sensor border"] = int(off.sum())
    for k, n in zip(*np.unique(lab, return_counts=True)):
        what = ("the lens's image circle" if k == L.VOID else names.get(int(k), str(k)))
        counts[what] = counts.get(what, 0) + int(n)
    share = 100.0 * int(hidden.sum()) / sil.area
    main = max(counts, key=lambda k: counts[k])
    if main in ("the sensor border", "the lens's image circle"):
        return f"is cut by {main} ({share:.1f} % of it)"
    return f"is {share:.1f} % hidden behind the {main}"
