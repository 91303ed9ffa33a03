"""The calibration board's corners in a capture, without predicted corners: whole or partial.

OpenCV's chessboard detector (``cv2.findChessboardCornersSB``) finds a board only when all
of its inner corners are in view and the grid is not too curved.  Real captures often show
less: a board close to the camera, cut by the image border or the lens's field, hidden in
part by the car's body, or strongly curved near the fisheye's edge.  :func:`detect_grids`
therefore looks in several places and accepts part of the board:

* the whole capture, and perspective (pinhole) views of it: one centred on the board's
  predicted direction, one looking straight at the board's predicted plane (squares stay
  square even for a board seen nearly edge-on at the fisheye's rim), then views tiling the
  lens's field (so a board is found wherever it lies, however wrong the scene's pose is); a
  pinhole view straightens the fisheye's curves;
* in each, first the whole board (``findChessboardCornersSB`` with the board's grid), then
  any part of it of at least :data:`MIN_PATCH` inner corners
  (``cv2.findChessboardCornersSBWithMeta`` with ``CALIB_CB_LARGER``: the smallest grid it
  must find is given, and it returns the largest it can grow).

Which of the board's corners a patch holds is not known here: that is the correspondence
(:mod:`.board_start`).

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  A grid is an array (rows, cols, 2) of capture pixels whose neighbours
along either axis are neighbouring corners of the board.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import cv2
import numpy as np

from ..camera import FisheyeCamera
from .board import BoardLayout

__all__ = ["GridDetection", "detect_grids", "MIN_PATCH", "view_basis"]

#: A partial board must show at least this many inner corners (rows, cols) to be used.
MIN_PATCH = (3, 3)
#: Perspective view around the board's predicted direction: margin, degrees.
VIEW_MARGIN_DEG = 20.0
#: Perspective view: pixels per board square at the view's centre.
VIEW_SQUARE_PX = 18.0
#: Perspective view: longest side, px.
VIEW_MAX_PX = 1200
#: Tiles: half-angle of each tile's view, degrees, and the tiles' directions (off-axis angle,
#: number of azimuths): two rings reaching the edge of a 200° lens, overlapping (the centre
#: is the whole image's and the predicted views').
TILE_HALF_DEG = 40.0
TILE_RINGS = ((45.0, 4), (80.0, 6))
#: Tiles of the rim's ring: their scale against the lens's own at its centre (the rim is
#: squeezed; the detector wants about 10 px or more per square).
TILE_ZOOM = 2.0


@dataclass(frozen=True)
class GridDetection:
    """Corners the detector found, as a grid.

    Attributes
    ----------
    corners : (rows, cols, 2) float
        Capture pixels, px.
    view : str
        Where they were found (``"whole image"``, ``"perspective view"``, ``"tile …"``).
    whole : bool
        The detector found the board's whole inner grid (else a part of it, or possibly more:
        the board's edge taken for a row).
    """

    corners: np.ndarray
    view: str
    whole: bool

    @property
    def n(self) -> int:
        """Number of corners."""
        return int(self.corners.shape[0] * self.corners.shape[1])


def _flags() -> int:

    return cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY


def _grids_in(img: np.ndarray, grid: tuple[int, int], pinhole: bool,
              whole_first: bool = True) -> Iterator[tuple[np.ndarray, bool]]:
    """The whole board's grid in ``img`` (rows = grid[1]; looked for first when
    ``whole_first``), else the part of it the detector grows from :data:`MIN_PATCH` (or, when
    that is not a plane's grid, from one size larger); (corners (rows, cols, 2) in ``img`` px,
    whole).  In a ``pinhole`` view a grid must be a plane's (:func:`_regular`)."""

    if whole_first:
        ok, found = cv2.findChessboardCornersSB(img, grid, flags=_flags())
        if ok and found is not None and len(found) == grid[0] * grid[1]:
            pts = np.asarray(found, np.float64).reshape(grid[1], grid[0], 2)
            if not pinhole or _regular(pts) is pts:
                yield pts, True
                return
    for k in range(2 if whole_first else 1):  # tiles: the smallest seed only
        size = (MIN_PATCH[0] + k, MIN_PATCH[1] + k)
        ok, found, meta = cv2.findChessboardCornersSBWithMeta(
            img, size, flags=_flags() | cv2.CALIB_CB_LARGER)
        if not ok or found is None or meta is None or len(found) != meta.size:
            return  # nothing from the smallest seed: nothing from a larger one either
        pts = np.asarray(found, np.float64).reshape(meta.shape[0], meta.shape[1], 2)
        kept = _regular(pts) if pinhole else pts
        if kept is not None:
            yield kept, kept.shape[:2] == (grid[1], grid[0])
            return


#: In a pinhole view a grid's corners lie within this share of their spacing of one
#: homography of the grid (a plane's); the detector's partial grids sometimes grow rows off
#: the board.
MAX_GRID_RESIDUAL = 0.12


def _regular(det: np.ndarray) -> np.ndarray | None:
    """``det`` (rows, cols, 2) px if one homography maps the grid onto it (residuals within
    :data:`MAX_GRID_RESIDUAL` of the spacing), else with its worst outer rows and columns
    dropped until it does; None when less than :data:`MIN_PATCH` is left."""

    while min(det.shape[:2]) >= min(MIN_PATCH):
        r, c = np.mgrid[0:det.shape[0], 0:det.shape[1]]
        src = np.stack([c.ravel(), r.ravel()], axis=1).astype(np.float64)
        dst = det.reshape(-1, 2)
        h, _ = cv2.findHomography(src, dst, 0)
        if h is None:
            return None
        proj = cv2.perspectiveTransform(src.reshape(-1, 1, 2), h).reshape(-1, 2)
        err = np.linalg.norm(proj - dst, axis=1).reshape(det.shape[:2])
        steps = np.concatenate([np.linalg.norm(np.diff(det, axis=a), axis=-1).ravel()
                                for a in (0, 1)])
        if err.max() <= MAX_GRID_RESIDUAL * float(np.median(steps)):
            return det
        sides = {"top": err[0].mean(), "bottom": err[-1].mean(), "left": err[:, 0].mean(),
                 "right": err[:, -1].mean()}
        side = max(sides, key=lambda k: sides[k])
        det = {"top": det[1:], "bottom": det[:-1], "left": det[:, 1:], "right": det[:, :-1]}[side]
    return None


def view_basis(direction: np.ndarray) -> np.ndarray:
    """Columns: x, y, z axes (camera frame) of a pinhole view looking along ``direction``,
    its x axis as close to the camera's as possible."""
    z = direction / np.linalg.norm(direction)
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = ref - (ref @ z) * z
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


@dataclass(frozen=True)
class _View:
    """A pinhole view of the capture: basis (camera frame), focal length and size, px."""

    basis: np.ndarray
    f: float
    n: int

    def image(self, grey_u8: np.ndarray, camera: FisheyeCamera) -> np.ndarray:
        """The view rendered from the capture (bilinear; black outside the lens's field)."""

        c = (self.n - 1) / 2
        vv, uu = np.mgrid[0:self.n, 0:self.n].astype(np.float64)
        rays = np.stack([(uu - c) / self.f, (vv - c) / self.f, np.ones_like(uu)], -1) @ self.basis.T
        uv, in_fov = camera.project_rays(rays.reshape(-1, 3))
        uv[~in_fov] = -10.0
        maps = uv.reshape(self.n, self.n, 2).astype(np.float32)
        return cv2.remap(grey_u8, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def to_capture(self, pts: np.ndarray, camera: FisheyeCamera) -> np.ndarray | None:
        """View pixels (..., 2) back to capture pixels; None if any leaves the field."""
        c = (self.n - 1) / 2
        flat = pts.reshape(-1, 2)
        rays = np.stack([(flat[:, 0] - c) / self.f, (flat[:, 1] - c) / self.f,
                         np.ones(len(flat))], -1) @ self.basis.T
        uv, ok = camera.project_rays(rays)
        if not np.all(ok):
            return None
        return np.asarray(uv, np.float64).reshape(pts.shape)


def _predicted_view(camera: FisheyeCamera, layout: BoardLayout) -> _View:
    """A view centred on the board's predicted direction (``camera``'s pose), wide enough
    for the board to lie anywhere within :data:`VIEW_MARGIN_DEG` of it, ≈
    :data:`VIEW_SQUARE_PX` px per square."""
    rays = camera.scene_to_camera(layout.corner_points.reshape(-1, 3))
    centre = rays.mean(axis=0)
    basis = view_basis(centre)
    unit = rays / np.linalg.norm(rays, axis=1, keepdims=True)
    spread = np.degrees(np.arccos(np.clip(unit @ basis[:, 2], -1, 1))).max()
    square_deg = np.degrees(layout.square_size / np.linalg.norm(centre))
    half = np.radians(min(spread + square_deg + VIEW_MARGIN_DEG, 65.0))
    f = VIEW_SQUARE_PX * np.linalg.norm(centre) / layout.square_size
    f = min(f, VIEW_MAX_PX / 2 / np.tan(half))
    return _View(basis, float(f), int(2 * f * np.tan(half)) + 1)


@dataclass(frozen=True)
class _PlaneView:
    """A view of the board's predicted plane, straight on: view pixel (x, y) is the plane
    point ``corner + (x / f) a + (y / f) b`` (m), seen through the lens from the camera's
    predicted pose.  Even a board seen nearly edge-on at the fisheye's rim shows square
    squares here, wherever the real camera is within a few degrees and decimetres."""

    corner: np.ndarray
    a: np.ndarray
    b: np.ndarray
    f: float
    size: tuple[int, int]

    def _uv(self, xy: np.ndarray, camera: FisheyeCamera) -> tuple[np.ndarray, np.ndarray]:
        pts = self.corner + (xy[:, :1] / self.f) * self.a + (xy[:, 1:] / self.f) * self.b
        return camera.project_rays(camera.scene_to_camera(pts))

    def image(self, grey_u8: np.ndarray, camera: FisheyeCamera) -> np.ndarray:
        """The view rendered from the capture (bilinear; black outside the lens's field)."""

        w, h = self.size
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
        uv, ok = self._uv(np.stack([xx.ravel(), yy.ravel()], axis=1), camera)
        uv[~ok] = -10.0
        maps = uv.reshape(h, w, 2).astype(np.float32)
        return cv2.remap(grey_u8, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def to_capture(self, pts: np.ndarray, camera: FisheyeCamera) -> np.ndarray | None:
        """View pixels (..., 2) back to capture pixels; None if any leaves the field."""
        uv, ok = self._uv(pts.reshape(-1, 2), camera)
        return None if not np.all(ok) else np.asarray(uv, np.float64).reshape(pts.shape)


#: Board-plane view: how far around the board (m) its plane is shown, and the view's
#: longest side (px).
PLANE_MARGIN_M = 1.0


def _plane_view(camera: FisheyeCamera, layout: BoardLayout) -> _PlaneView | None:
    """The board's plane around its predicted place, ≈ :data:`VIEW_SQUARE_PX` px per square
    (fewer for a large area), oriented with ``b`` pointing up; None when the camera is
    behind the plane."""
    if (camera.position - layout.origin) @ layout.normal <= 0:
        return None
    s = layout.square_size
    w_m = (layout.grid[0] + 1) * s + 2 * PLANE_MARGIN_M
    h_m = (layout.grid[1] + 1) * s + 2 * PLANE_MARGIN_M
    f = min(VIEW_SQUARE_PX / s, VIEW_MAX_PX / max(w_m, h_m))
    top_left = layout.origin - (s + PLANE_MARGIN_M) * layout.a \
        + (layout.grid[1] * s + PLANE_MARGIN_M) * layout.b
    return _PlaneView(top_left, layout.a, -layout.b, float(f),
                      (int(w_m * f) + 1, int(h_m * f) + 1))


def _tiles(camera: FisheyeCamera) -> list[tuple[str, _View]]:
    """Views tiling the lens's field (:data:`TILE_RINGS`), each :data:`TILE_HALF_DEG` wide
    on every side, at about the lens's own resolution at its centre (the rim's ring
    :data:`TILE_ZOOM` times finer); tiles whose centre is off the sensor are left out."""
    half = np.radians(TILE_HALF_DEG)
    out = []
    for ring, (off_deg, count) in enumerate(TILE_RINGS):
        if off_deg - TILE_HALF_DEG >= camera.fov_deg / 2:
            continue
        zoom = TILE_ZOOM if ring == len(TILE_RINGS) - 1 else 1.0
        f = float(np.clip(zoom * 0.5 * (camera.fx + camera.fy), 50.0,
                          VIEW_MAX_PX / 2 / np.tan(half)))
        n = int(2 * f * np.tan(half)) + 1
        for k in range(count):
            az = 2 * np.pi * k / count
            t = np.radians(off_deg)
            d = np.array([np.sin(t) * np.cos(az), np.sin(t) * np.sin(az), np.cos(t)])
            uv, ok = camera.project_rays(d[None])
            if not (ok[0] and 0 <= uv[0, 0] <= camera.width - 1
                    and 0 <= uv[0, 1] <= camera.height - 1):
                continue
            out.append((f"tile {off_deg:.0f}°/{np.degrees(az):.0f}°", _View(view_basis(d), f, n)))
    return out


def detect_grids(grey_f: np.ndarray, camera: FisheyeCamera, layout: BoardLayout,
                 places: tuple[str, ...] = ("whole image", "perspective view",
                                            "board plane view", "tiles"),
                 ) -> Iterator[GridDetection]:
    """The board's corners found in the capture, place by place (lazily: stop when one is
    good enough).

    Parameters
    ----------
    grey_f : (H, W) float32
        The capture's grey level.
    camera : FisheyeCamera
        The scene's camera at the scene's pose (for the predicted view).
    layout : BoardLayout
    places : tuple of str
        Where to look, in order: ``"whole image"``, ``"perspective view"`` (around the
        board's predicted direction), ``"board plane view"`` (the board's predicted plane
        straight on, :data:`PLANE_MARGIN_M` around it), ``"tiles"`` (views tiling the lens's
        field).

    Yields
    ------
    GridDetection
        Per place (per tile), the whole board's grid or the largest part of it found.
    """
    grey_u8 = np.clip(grey_f, 0, 255).astype(np.uint8)
    grid = layout.grid
    for place in places:
        if place == "whole image":
            for pts, whole in _grids_in(grey_u8, grid, pinhole=False):
                yield GridDetection(pts, place, whole)
            continue
        views: list[tuple[str, _View | _PlaneView]] = []
        if place == "perspective view":
            views.append((place, _predicted_view(camera, layout)))
        elif place == "board plane view":
            plane = _plane_view(camera, layout)
            views += [] if plane is None else [(place, plane)]
        else:
            views += _tiles(camera)
        for name, view in views:
            for pts, whole in _grids_in(view.image(grey_u8, camera), grid, pinhole=True,
                                        whole_first=not name.startswith("tile")):
                back = view.to_capture(pts, camera)
                back = None if back is None else _inside(back, grey_f.shape)
                if back is not None:
                    yield GridDetection(back, name, whole and back.shape == pts.shape)


def _inside(det: np.ndarray, shape: tuple[int, ...]) -> np.ndarray | None:
    """The grid ``det`` (rows, cols, 2) px without its outer rows and columns that hold a
    corner outside the image (within 2 px of its border); None when less than
    :data:`MIN_PATCH` is left."""
    h, w = shape[:2]
    while det.size:
        bad = (det[..., 0] < 2) | (det[..., 1] < 2) | (det[..., 0] > w - 3) | (det[..., 1] > h - 3)
        if not bad.any():
            break
        edges = {"top": bad[0].sum(), "bottom": bad[-1].sum(), "left": bad[:, 0].sum(),
                 "right": bad[:, -1].sum()}
        side = max(edges, key=lambda k: edges[k])
        det = {"top": det[1:], "bottom": det[:-1], "left": det[:, 1:], "right": det[:, :-1]}[side]
    if min(det.shape[:2]) < min(MIN_PATCH) or det.size < 2 * MIN_PATCH[0] * MIN_PATCH[1]:
        return None
    return det
