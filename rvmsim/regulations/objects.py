"""The FMVSS test objects as the camera sees them: silhouettes and width edges in the fisheye
image, computed analytically once per scene (for ECs 1-5, 1-6 and 6-1, :mod:`.fmvss111`).

Written against the public API (:class:`rvmsim.criteria.SceneContext`, the scene and the
camera), like any customer's plugin helper.

Conventions: scene frame of :mod:`rvmsim.camera` (x toward the driver's side, y toward the
ground, z rearward, metres; an object stands on y = 0 and reaches up to y = −height);
fisheye pixel centres at integer coordinates.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import cv2
import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..scene import Scene
from ..criteria.context import SceneContext
from ..criteria.measure import LabelSource

__all__ = ["ObjectSilhouette", "WidthEdges", "silhouette", "width_edges", "object_cylinder",
           "silhouette_fractions", "standing_alone_labels"]

#: Fisheye px beyond the image kept around a silhouette (parts there count as not visible).
_MARGIN_PX = 2
#: Azimuths sampled on the top and bottom circles to bound a silhouette.
_RING = 96


def object_cylinder(scene: Scene, letter: str) -> tuple[float, float, float, float] | None:
    """(x, z, radius, height) of test object ``letter``, metres: an FMVSS letter (A–G), or
    the name of an object of the scene's site (:class:`rvmsim.scene.SiteObject`, e.g.
    ``row2.1``); None when the scene has no such object (disabled, or another site)."""
    site = scene.test_site
    if letter in L.OBJECT_LETTERS:
        centre = site.object_centre(letter)
        if centre is None:
            return None
        return (centre[0], centre[1], site.object_diameter / 2.0, site.object_height)
    for obj in site.site_objects:
        if obj.name == letter:
            return (obj.x, obj.z, obj.radius, obj.height)
    return None


@dataclass(frozen=True)
class ObjectSilhouette:
    """One object's silhouette in the fisheye image, hidden parts included.

    ``box`` = (x0, y0) fisheye px of the masks' top-left pixel (may lie outside the image);
    ``inner`` (h, w) uint8 255 where the silhouette, eroded by 1 px, lies (its boundary
    pixels are left out: the rendered mesh and the analytic cylinder may disagree there by
    a fraction of a pixel); ``visible`` the same pixels where the rendered label image
    shows the object itself (not hidden, inside the image); ``area`` and ``visible_area``
    their pixel counts; ``outline`` the silhouette's
    outer contour, fisheye px (N, 2) float64, for drawings.
    """

    box: tuple[int, int]
    inner: np.ndarray
    visible: np.ndarray
    area: int
    visible_area: int
    outline: np.ndarray


def _ray_hits(origin: np.ndarray, dirs: np.ndarray, cyl: tuple[float, float, float, float]
              ) -> np.ndarray:
    """Which rays (N, 3) from ``origin`` hit the closed cylinder (side or top), (N,) bool."""
    cx, cz, r, h = cyl
    ox, oy, oz = origin[0] - cx, origin[1], origin[2] - cz
    dx, dy, dz = dirs[:, 0], dirs[:, 1], dirs[:, 2]
    a = dx * dx + dz * dz
    b = 2.0 * (ox * dx + oz * dz)
    c = ox * ox + oz * oz - r * r
    disc = b * b - 4.0 * a * c
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * np.maximum(a, 1e-300))
        y = oy + t * dy
        side = (disc >= 0) & (t > 0) & (y <= 0.0) & (y >= -h)
        t_top = (-h - oy) / np.where(dy != 0, dy, 1e-300)
        tx, tz = ox + t_top * dx, oz + t_top * dz
        top = (t_top > 0) & (tx * tx + tz * tz <= r * r)
    return side | top


def _bounds(camera: FisheyeCamera, cyl: tuple[float, float, float, float]
            ) -> tuple[int, int, int, int] | None:
    """Fisheye px box (x0, y0, x1, y1), exclusive ends, holding the projected cylinder,
    clipped to the image grown by half its size; None when nothing of it is in front."""
    cx, cz, r, h = cyl
    az = np.linspace(0.0, 2.0 * math.pi, _RING, endpoint=False)
    rim = np.stack([cx + r * np.sin(az), np.zeros_like(az), cz + r * np.cos(az)], 1)
    pts = np.concatenate([rim, rim + [0.0, -h, 0.0], [[cx, -h / 2, cz]]])
    uv, in_fov = camera.project(pts)
    if not np.any(in_fov):
        return None
    w, hh = camera.width, camera.height
    lo = np.floor(uv.min(axis=0)).astype(int) - _MARGIN_PX - 2
    hi = np.ceil(uv.max(axis=0)).astype(int) + _MARGIN_PX + 3
    x0, y0 = max(int(lo[0]), -w // 2), max(int(lo[1]), -hh // 2)
    x1, y1 = min(int(hi[0]), w + w // 2), min(int(hi[1]), hh + hh // 2)
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def _compute_silhouette(ctx: SceneContext, letter: str) -> ObjectSilhouette | None:

    cyl = object_cylinder(ctx.scene, letter)
    cam = ctx.camera
    box = None if cyl is None else _bounds(cam, cyl)
    if cyl is None or box is None:
        return None
    x0, y0, x1, y1 = box
    u, v = np.meshgrid(np.arange(x0, x1, dtype=np.float64), np.arange(y0, y1, dtype=np.float64))
    rays, in_fov = cam.pixel_rays(np.stack([u, v], axis=-1))
    dirs = rays.reshape(-1, 3) @ cam.rotation.T  # camera → scene frame
    hit = _ray_hits(cam.position, dirs, cyl).reshape(u.shape) & in_fov
    mask = hit.astype(np.uint8) * 255
    # the rendered label image over the same box (void outside the image)
    labels = ctx.fisheye_labels
    crop = np.zeros(mask.shape, np.uint8)
    ix0, iy0 = max(x0, 0), max(y0, 0)
    ix1, iy1 = min(x1, labels.shape[1]), min(y1, labels.shape[0])
    if ix1 > ix0 and iy1 > iy0:
        crop[iy0 - y0 : iy1 - y0, ix0 - x0 : ix1 - x0] = labels[iy0:iy1, ix0:ix1]
    own = cv2.LUT(crop, L.lut(_silhouette_labels(ctx.scene, letter)))
    inner = cv2.erode(mask, np.ones((3, 3), np.uint8), borderType=cv2.BORDER_CONSTANT,
                      borderValue=0)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    outline = (max(contours, key=len).reshape(-1, 2).astype(np.float64) + (x0, y0)
               if contours else np.zeros((0, 2)))
    visible = cv2.bitwise_and(inner, own)
    return ObjectSilhouette((x0, y0), inner, visible, int(cv2.countNonZero(inner)),
                            int(cv2.countNonZero(visible)), outline)


def _silhouette_labels(scene: Scene, letter: str) -> tuple[int, ...]:
    """What shows object ``letter`` in the label image: FMVSS letters their body and stripe
    (as EC 1-5 has always counted them); a site object any site object's label, since a
    site's objects do not hide one another (:func:`standing_alone_labels`)."""
    if letter in L.OBJECT_LETTERS:
        return (L.object_body(letter), L.object_stripe(letter))
    return standing_alone_labels(scene, letter)


def standing_alone_labels(scene: Scene, name: str) -> tuple[int, ...]:
    """Labels that count as showing site object ``name``: its own and every other object's
    of the site.  Each object of a site definition is judged as if it stood alone (⚠ the
    regulations test one position at a time: with all rows placed at once the near row
    would hide the far rows' centre objects).  Exact as long as only other test objects
    stand between an object and the camera, never the car body: the body is nearer the
    camera than every object behind the car."""
    if not any(o.name == name for o in scene.test_site.site_objects):
        return ()
    return tuple(k for o in scene.test_site.site_objects for k in o.labels)


def silhouette(ctx: SceneContext, letter: str) -> ObjectSilhouette | None:
    """Object ``letter``'s silhouette (computed once per scene; None when the object is
    disabled or wholly outside the lens's field)."""
    return ctx.shared(("fmvss111.silhouette", letter), lambda: _compute_silhouette(ctx, letter))


@dataclass(frozen=True)
class WidthEdges:
    """The two ends of an object's horizontal width as the camera sees it: the points where
    the lines of sight touch the cylinder, at half its height.

    ``points`` (2, 2) fisheye px (left and right as seen from the camera), ``centre`` (1, 2)
    fisheye px of the axis at half height, ``angle_deg`` the angle between the two lines of
    sight, degrees.
    """

    points: np.ndarray
    centre: np.ndarray
    angle_deg: float


def _compute_edges(ctx: SceneContext, letter: str) -> WidthEdges | None:
    cyl = object_cylinder(ctx.scene, letter)
    if cyl is None:
        return None
    cx, cz, r, h = cyl
    cam = ctx.camera
    ex, ez = float(cam.position[0]) - cx, float(cam.position[2]) - cz
    dist = math.hypot(ex, ez)
    if dist <= r:
        return None
    base = math.atan2(ex, ez)  # azimuth (from +z toward +x) of the camera seen from the axis
    alpha = math.acos(r / dist)  # tangent points lie ±alpha from that azimuth
    y = -h / 2.0
    pts = np.array([[cx + r * math.sin(base + s * alpha), y, cz + r * math.cos(base + s * alpha)]
                    for s in (-1.0, 1.0)] + [[cx, y, cz]])
    uv, in_fov = cam.project(pts)
    if not np.all(in_fov):
        return None
    rays = cam.scene_to_camera(pts[:2])
    cos = float(np.dot(rays[0], rays[1]) / (np.linalg.norm(rays[0]) * np.linalg.norm(rays[1])))
    return WidthEdges(uv[:2], uv[2:], math.degrees(math.acos(min(1.0, max(-1.0, cos)))))


def width_edges(ctx: SceneContext, letter: str) -> WidthEdges | None:
    """Object ``letter``'s width edges (once per scene; None when disabled or out of the
    lens's field)."""
    return ctx.shared(("fmvss111.width", letter), lambda: _compute_edges(ctx, letter))


def silhouette_fractions(src: LabelSource, names: Iterable[str]
                         ) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    """Per object of ``names`` in the scene: the percentage of its whole silhouette (hidden
    parts included) that the candidate's RVM image shows, and its fisheye outline.

    Visible: the label image shows the object there (:func:`silhouette`) and the pixel lies
    inside the RVM image's footprint in the fisheye image.  Objects absent from the scene or
    wholly outside the lens's field are left out.  Needs ``src.context`` and ``src.isp``
    (empty results without).
    """

    ctx, isp = src.context, src.isp
    if ctx is None or isp is None:
        return {}, {}
    poly = src.shared(("footprint", 32), lambda: isp.footprint(32))
    contour = poly.astype(np.float32).reshape(-1, 1, 2)
    fractions: dict[str, float] = {}
    outlines: dict[str, np.ndarray] = {}
    for letter in names:
        sil = silhouette(ctx, letter)
        if sil is None or sil.area == 0:
            continue
        h, w = sil.inner.shape
        centre = (sil.box[0] + (w - 1) / 2.0, sil.box[1] + (h - 1) / 2.0)
        if cv2.pointPolygonTest(contour, centre, True) > math.hypot(w, h) / 2.0 + 1.0:
            seen = sil.visible_area  # the RVM border is farther than the whole box: all in
        else:
            inside = np.zeros((h, w), np.uint8)
            pts = np.round((poly - sil.box) * 16.0).astype(np.int32).reshape(-1, 1, 2)
            cv2.fillPoly(inside, [pts], 255, cv2.LINE_8, shift=4)
            seen = cv2.countNonZero(cv2.bitwise_and(sil.visible, inside))
        fractions[letter] = 100.0 * seen / sil.area
        outlines[letter] = sil.outline
    return fractions, outlines
