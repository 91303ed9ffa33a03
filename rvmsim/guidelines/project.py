"""Guidelines through the lens and the ISP: ground points → fisheye pixels (the camera's real
lens, :meth:`rvmsim.camera.FisheyeCamera.project`) → display pixels of the RVM image (the ISP
map's exact inverse, :func:`rvmsim.isp.input_to_output`), cut where they leave the picture.

A ground point is *shown* when its ray lies in the lens's field of view, lands on the
fisheye sensor, meets the ISP's virtual image plane in front, and lands on the RVM image.
Lines are cut at the border of what is shown: the crossing is found by bisection on the
ground between the last shown and the first hidden sample (to 1e-6 of the step).

Convention
----------
Ground points (x, z) m in the scene frame (y = 0); pixel centres at integer coordinates in
both images, so the RVM image spans [−0.5, W − 0.5] × [−0.5, H − 0.5] px.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera
from ..isp import IspParams, OutputSpec, input_to_output
from ..isp.exact import map_points
from .lines import GroundLine

__all__ = ["GuidelineView", "DisplayPiece", "DisplayLine", "project_lines", "display_to_ground"]

_BISECTIONS = 24


@dataclass(frozen=True)
class GuidelineView:
    """The camera (its real lens and pose) and the ISP setting that show the ground.

    Attributes
    ----------
    camera : FisheyeCamera
    params : IspParams
    output : OutputSpec
        The RVM image the lines are drawn on (the image of record).
    """

    camera: FisheyeCamera
    params: IspParams
    output: OutputSpec

    def to_display(self, ground_xz: np.ndarray, height_m: float = 0.0
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Display px (N, 2) of ground points (N, 2) (x, z) m, and whether each is shown;
        ``height_m``: the points lie that far above the ground (a painted strip's lift).

        Convention
        ----------
        See the module docstring.
        """
        g = np.asarray(ground_xz, np.float64).reshape(-1, 2)
        pts = np.column_stack([g[:, 0], np.full(len(g), -height_m), g[:, 1]])
        cam = self.camera
        uv_in, in_fov = cam.project(pts)
        on_sensor = ((uv_in[:, 0] >= -0.5) & (uv_in[:, 0] <= cam.width - 0.5)
                     & (uv_in[:, 1] >= -0.5) & (uv_in[:, 1] <= cam.height - 0.5))
        uv, in_front = input_to_output(self.params, uv_in, (cam.width, cam.height),
                                       self.output)
        w, h = self.output.width, self.output.height
        finite = np.isfinite(uv).all(axis=1)
        uv = np.where(finite[:, None], uv, np.nan)
        with np.errstate(invalid="ignore"):
            on_image = ((uv[:, 0] >= -0.5) & (uv[:, 0] <= w - 0.5)
                        & (uv[:, 1] >= -0.5) & (uv[:, 1] <= h - 0.5))
        return uv, in_fov & on_sensor & in_front & finite & on_image


@dataclass(frozen=True, eq=False)
class DisplayPiece:
    """A shown stretch of a line: display px ``uv_px`` (M, 2) and the ground points
    ``ground_m`` (M, 2) (x, z) m they come from; the ends at a cut lie on the border."""

    uv_px: np.ndarray
    ground_m: np.ndarray


@dataclass(frozen=True, eq=False)
class DisplayLine:
    """A guideline on the RVM image: its ground line's name, kind, colour and steering angle,
    and the pieces of it that are shown (none: the line is out of the picture)."""

    name: str
    kind: str
    color: tuple[float, float, float]
    steering_deg: float | None
    pieces: tuple[DisplayPiece, ...]

    @property
    def shown(self) -> bool:
        return bool(self.pieces)


def _crossings(view: GuidelineView, inside: np.ndarray, outside: np.ndarray,
               height_m: float) -> np.ndarray:
    """The shown end (ground (K, 2) m) of each segment from a shown ``inside`` point to a
    hidden ``outside`` point, by bisection."""
    a, b = inside.copy(), outside.copy()
    for _ in range(_BISECTIONS):
        mid = (a + b) / 2.0
        _, vis = view.to_display(mid, height_m)
        a = np.where(vis[:, None], mid, a)
        b = np.where(vis[:, None], b, mid)
    return a


def project_lines(view: GuidelineView, lines: Sequence[GroundLine], *,
                  height_m: float = 0.0) -> list[DisplayLine]:
    """Every line on the RVM image, cut at the border of what is shown.

    Parameters
    ----------
    view : GuidelineView
    lines : sequence of GroundLine
    height_m : float
        The lines lie this far above the ground, m (0: on it, as guidelines are).

    Returns
    -------
    list of DisplayLine
        In the order of ``lines``.

    Convention
    ----------
    See the module docstring.  All lines' points are projected in one batch.
    """
    if not lines:
        return []
    counts = [len(line.points_m) for line in lines]
    ground = np.concatenate([line.points_m for line in lines])
    uv, vis = view.to_display(ground, height_m)
    starts = np.cumsum([0, *counts[:-1]])
    # segments whose ends differ in being shown, over all lines at once
    same_line = np.ones(len(ground) - 1, bool)
    same_line[starts[1:] - 1] = False
    edge = same_line & (vis[:-1] != vis[1:])
    idx = np.flatnonzero(edge)
    inner = np.where(vis[idx], idx, idx + 1)
    outer = np.where(vis[idx], idx + 1, idx)
    cut = _crossings(view, ground[inner], ground[outer], height_m)
    cut_uv, _ = view.to_display(cut, height_m)
    cut_at = dict(zip(idx.tolist(), range(len(idx))))
    out: list[DisplayLine] = []
    for line, start, n in zip(lines, starts.tolist(), counts):
        pieces: list[DisplayPiece] = []
        i = start
        while i < start + n:
            if not vis[i]:
                i += 1
                continue
            j = i
            while j + 1 < start + n and vis[j + 1]:
                j += 1
            g = [ground[i:j + 1]]
            p = [uv[i:j + 1]]
            if i > start and (i - 1) in cut_at:
                k = cut_at[i - 1]
                g.insert(0, cut[k:k + 1])
                p.insert(0, cut_uv[k:k + 1])
            if j + 1 < start + n and j in cut_at:
                k = cut_at[j]
                g.append(cut[k:k + 1])
                p.append(cut_uv[k:k + 1])
            gg, pp = np.concatenate(g), np.concatenate(p)
            if len(gg) >= 2:
                pieces.append(DisplayPiece(pp, gg))
            i = j + 1
        out.append(DisplayLine(line.name, line.kind, line.color, line.steering_deg,
                               tuple(pieces)))
    return out


def display_to_ground(view: GuidelineView, uv_px: np.ndarray, height_m: float = 0.0
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Where on the ground display pixels look: (N, 2) (x, z) m, and whether the pixel's ray
    meets the ground (the ISP's exact map into the fisheye image, the lens's ray, the ground
    plane y = 0 ahead of the camera; the plane ``height_m`` above it when given).

    Convention
    ----------
    Display px with pixel centres at integer coordinates; scene frame, metres.  The inverse
    of :meth:`GuidelineView.to_display` for shown points.
    """
    uv = np.asarray(uv_px, np.float64).reshape(-1, 2)
    cam = view.camera
    ux, vy, _ = map_points(view.params, uv[:, 0], uv[:, 1], (cam.width, cam.height), view.output)
    rays, in_fov = cam.pixel_rays(np.column_stack([ux, vy]))
    d = rays @ cam.rotation.T  # camera → scene directions
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (-height_m - cam.position[1]) / d[:, 1]
    hits = in_fov & np.isfinite(lam) & (lam > 0)
    lam = np.where(hits, lam, np.nan)
    ground = cam.position[[0, 2]][None, :] + lam[:, None] * d[:, [0, 2]]
    return ground, hits
