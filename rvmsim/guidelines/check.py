"""The guidelines checked through the renderer: the same lines painted on the site's ground,
rendered, run through the ISP, and measured in the RVM label image (labels-based).

For each line the check paints a strip :data:`PAINT_WIDTH_M` wide along its ground polyline
(:class:`~rvmsim.scene.PaintedLine`, a label of its own), renders the scene (the site's own
painted guidelines and test objects left out, so nothing hides or crosses the strips), maps
the RVM image of record's labels from the fisheye labels with the ISP's exact map (nearest,
as the ISP maps labels, read at sub-pixel points: no second quantisation by the RVM pixel
grid), and at points every :data:`SAMPLE_STEP_PX` along the overlay scans across it: the
strip's two edges in the label image give its centre, and the overlay's signed distance to
that centre is the offset.  A line's offset is the largest mean over :data:`SMOOTH_SCANS`
consecutive scans (a single scan is quantised by the label pixels).  A scan counts only when the strip lies whole between ground on both sides (not cut
by the picture's border, the body, or another line).  The strip's centre is the image of
the line's centre to second order (a strip 5 cm wide: < 0.1 px).  The strips lie
:data:`~rvmsim.scene.site.PAINTED_LINE_LIFT_M` above the ground (against depth fighting), which
moves them about 0.3 px up a 1280 × 720 image: the lines are projected at that height for
the comparison, so the lift is not counted as an offset.

Lines are painted in groups that do not overlap: the static lines (marks and width lines),
then one group per steering angle (its two trajectory lines): every group is one render.

The same measurement is the EC family ``G-1`` (static lines) and ``G-2`` (trajectories) of
:mod:`rvmsim.guidelines.ecs`, on any scene whose site carries painted lines.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .. import labels as L
from ..isp import IspParams, OutputSpec
from ..isp.exact import map_points
from ..render import cached_render
from ..scene import PaintedLine, Scene, TestObject, scene_vehicle_width
from ..scene.guideline_spec import LineKind
from ..scene.site import PAINTED_LINE_LIFT_M
from .kinematics import running_gear
from .lines import GroundLine, static_lines, trajectory_lines
from .overlay import guideline_view, scene_spec
from .project import GuidelineView, display_to_ground, project_lines

__all__ = ["STATIC_KINDS", "TRAJECTORY_KINDS", "PAINT_WIDTH_M", "SAMPLE_STEP_PX", "LineCheck", "GuidelineCheck", "painted_lines",
           "painted_scene", "measure_painted", "check_guidelines", "check_angles"]

#: The line kinds G-1 judges (the static lines) and G-2 judges (the trajectories).
STATIC_KINDS: tuple[LineKind, ...] = ("mark", "width")
TRAJECTORY_KINDS: tuple[LineKind, ...] = ("trajectory",)
#: Width of a painted check line, m.
PAINT_WIDTH_M = 0.05
#: Spacing of the scans along a line, display px.
SAMPLE_STEP_PX = 2.0
#: Consecutive scans a line's offset is averaged over (≈ 18 px of line): a scan's centre is
#: quantised by the fisheye label pixels (± 0.5 px each edge), a line's place is not.
SMOOTH_SCANS = 9
_SCAN_STEP_PX = 0.125


@dataclass(frozen=True, eq=False)
class LineCheck:
    """One line's offsets from its painted strip.

    Attributes
    ----------
    name, kind : str
    steering_deg : float or None
    offsets_px : (S,) float64
        Signed overlay-to-strip-centre distance at each counted scan, display px (positive
        along the overlay's left normal).
    ground_m : (S, 2) float64
        The ground points (x, z) m of those scans.
    scans : int
        Scans tried (the counted ones are ``len(offsets_px)``).
    ground_offsets_m : (S,) float64
        The offsets on the ground: the distance (m, signed as ``offsets_px``) from the
        overlay's ground point to where the display point at the strip's centre looks.
    """

    name: str
    kind: str
    steering_deg: float | None
    offsets_px: np.ndarray
    ground_m: np.ndarray
    scans: int
    ground_offsets_m: np.ndarray

    @property
    def measured(self) -> bool:
        return len(self.offsets_px) > 0

    def stat(self, q: float) -> float:
        """The ``q``-quantile (0–1) of |offset|, px (NaN when nothing was measured)."""
        return float(np.quantile(np.abs(self.offsets_px), q)) if self.measured else float("nan")

    @property
    def p95_px(self) -> float:
        return self.stat(0.95)

    @property
    def offset_px(self) -> float:
        """The line's offset: the largest |mean offset| over :data:`SMOOTH_SCANS`
        consecutive counted scans (over all of them when fewer), px; NaN when nothing was
        measured.  This is the value G-1 and G-2 judge."""
        return _smoothed_max(self.offsets_px)

    @property
    def offset_cm(self) -> float:
        """:attr:`offset_px`'s measure of :attr:`ground_offsets_m`, in cm on the ground."""
        return 100.0 * _smoothed_max(self.ground_offsets_m)

    @property
    def max_px(self) -> float:
        return self.stat(1.0)

    @property
    def median_px(self) -> float:
        return self.stat(0.5)


def _smoothed_max(values: np.ndarray) -> float:
    """The largest |mean| over :data:`SMOOTH_SCANS` consecutive values (all when fewer);
    NaN for none."""
    if not len(values):
        return float("nan")
    k = min(SMOOTH_SCANS, len(values))
    return float(np.max(np.abs(np.convolve(values, np.full(k, 1.0 / k), mode="valid"))))


@dataclass(frozen=True, eq=False)
class GuidelineCheck:
    """The check of one car's guidelines: every line's :class:`LineCheck`."""

    output: OutputSpec
    lines: tuple[LineCheck, ...]

    def worst_px(self, kinds: Sequence[str]) -> float:
        """The largest :attr:`LineCheck.offset_px` over the measured lines of ``kinds``."""
        vals = [c.offset_px for c in self.lines if c.kind in kinds and c.measured]
        return max(vals) if vals else float("nan")


def painted_lines(lines: Sequence[GroundLine], width_m: float = PAINT_WIDTH_M
                  ) -> tuple[PaintedLine, ...]:
    """The lines as painted strips, labelled in order (:func:`rvmsim.labels.guide_paint`)."""
    return tuple(PaintedLine(index=i, points=tuple(map(tuple, line.points_m.tolist())),
                             width=width_m, color=line.color, name=line.name, kind=line.kind,
                             steering_deg=line.steering_deg)
                 for i, line in enumerate(lines))


def painted_scene(scene: Scene, lines: Sequence[GroundLine],
                  width_m: float = PAINT_WIDTH_M) -> Scene:
    """``scene`` with ``lines`` painted on the ground, and without the site's own painted
    guidelines and test objects A–G."""
    site = scene.test_site
    update: dict[str, object] = {"painted_lines": painted_lines(lines, width_m)}
    if site.fmvss:
        update["guidelines"] = site.guidelines.model_copy(update={"enabled": False})
        update["objects"] = {k: TestObject(enabled=False) for k in L.OBJECT_LETTERS}
    return scene.model_copy(update={"test_site": site.model_copy(update=update)})


def _resample(uv: np.ndarray, ground: np.ndarray, step: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points every ``step`` px along a display polyline, their unit left normals, and the
    ground points (linear between the polyline's points)."""
    seg = np.hypot(*np.diff(uv, axis=0).T)
    s = np.r_[0.0, np.cumsum(seg)]
    if s[-1] <= 0:
        return np.empty((0, 2)), np.empty((0, 2)), np.empty((0, 2))
    at = np.arange(step / 2, s[-1], step)
    p = np.column_stack([np.interp(at, s, uv[:, 0]), np.interp(at, s, uv[:, 1])])
    g = np.column_stack([np.interp(at, s, ground[:, 0]), np.interp(at, s, ground[:, 1])])
    h = min(step / 2, 0.5)
    a = np.column_stack([np.interp(at - h, s, uv[:, 0]), np.interp(at - h, s, uv[:, 1])])
    b = np.column_stack([np.interp(at + h, s, uv[:, 0]), np.interp(at + h, s, uv[:, 1])])
    t = b - a
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-12)
    return p, np.column_stack([t[:, 1], -t[:, 0]]), g


def _rvm_labels_at(fisheye_labels: np.ndarray, view: GuidelineView, xy: np.ndarray
                   ) -> np.ndarray:
    """The RVM label image at display points ``xy`` (..., 2) px, between pixel centres too:
    the ISP's exact map into the fisheye labels, nearest (what the ISP's nearest remap gives
    at pixel centres); VOID off the RVM image and where the map leaves the fisheye image."""
    h_i, w_i = fisheye_labels.shape
    w, h = view.output.width, view.output.height
    u, v = xy[..., 0], xy[..., 1]
    ux, vy, _ = map_points(view.params, u, v, (w_i, h_i), view.output)
    col, row = np.rint(ux), np.rint(vy)
    ok = ((u >= -0.5) & (u <= w - 0.5) & (v >= -0.5) & (v <= h - 0.5)
          & (col >= 0) & (col < w_i) & (row >= 0) & (row < h_i))
    col = np.clip(np.nan_to_num(col), 0, w_i - 1).astype(np.int64)
    row = np.clip(np.nan_to_num(row), 0, h_i - 1).astype(np.int64)
    return np.where(ok, fisheye_labels[row, col], L.VOID)


def _scan(fisheye_labels: np.ndarray, view: GuidelineView, points: np.ndarray,
          normals: np.ndarray, label: int, reach: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre offsets (px) of the strip ``label`` across each point, and whether counted."""
    n_t = int(np.ceil(reach.max() / _SCAN_STEP_PX))
    t = np.arange(-n_t, n_t + 1) * _SCAN_STEP_PX
    xy = points[:, None, :] + t[None, :, None] * normals[:, None, :]
    lab = _rvm_labels_at(fisheye_labels, view, xy)
    lab = np.where(np.abs(t)[None, :] <= reach[:, None], lab, L.VOID)
    on = lab == label
    T = len(t)
    idx = np.arange(T)
    centre = np.argmin(np.where(on, np.abs(t)[None, :], np.inf), axis=1)
    rows = np.arange(len(points))
    left_out = np.maximum.accumulate(np.where(~on, idx, -1), axis=1)
    right_out = np.minimum.accumulate(np.where(~on, idx, T)[:, ::-1], axis=1)[:, ::-1]
    lo = left_out[rows, centre] + 1
    hi = right_out[rows, centre] - 1
    ok = on[rows, centre] & (lo > 0) & (hi < T - 1)
    lo_c, hi_c = np.clip(lo - 1, 0, T - 1), np.clip(hi + 1, 0, T - 1)
    ok &= (lab[rows, lo_c] == L.GROUND) & (lab[rows, hi_c] == L.GROUND)
    offsets = (t[np.clip(lo, 0, T - 1)] + t[np.clip(hi, 0, T - 1)]) / 2.0
    return offsets, ok


def measure_painted(fisheye_labels: np.ndarray, view: GuidelineView,
                    painted: Sequence[PaintedLine]) -> list[LineCheck]:
    """Each painted line's offsets in the RVM label image ``view`` makes.

    Parameters
    ----------
    fisheye_labels : (H_i, W_i) uint8
        The fisheye label image of a scene carrying ``painted``, rendered with
        ``view.camera``; the RVM label image is read from it through the ISP's exact map
        (nearest), at the scans' sub-pixel points.
    view : GuidelineView
    painted : sequence of PaintedLine

    Returns
    -------
    list of LineCheck
        In the order of ``painted``.

    Convention
    ----------
    Display px, pixel centres at integer coordinates; scans skip the last strip width (in
    ground metres) at each end of a line, where its end cap would be measured.
    """
    lines = [GroundLine(p.name, p.kind, p.color, np.asarray(p.points, np.float64),
                        p.steering_deg) for p in painted]
    # the strips lie PAINTED_LINE_LIFT_M above the ground (against depth fighting): their
    # centrelines there are what the overlay is compared with (1 mm moves a line 0.3 px)
    lift = PAINTED_LINE_LIFT_M
    shown = project_lines(view, lines, height_m=lift)
    out: list[LineCheck] = []
    for p, line in zip(painted, shown):
        offs, grounds, metres, scans = [], [], [], 0
        ends = np.asarray(p.points, np.float64)[[0, -1]]
        for piece in line.pieces:
            pts, normals, ground = _resample(piece.uv_px, piece.ground_m, SAMPLE_STEP_PX)
            if not len(pts):
                continue
            away = np.min(np.linalg.norm(ground[:, None, :] - ends[None], axis=2), axis=1)
            keep = away > p.width
            pts, normals, ground = pts[keep], normals[keep], ground[keep]
            if not len(pts):
                continue
            # the strip's half width in display px at each point, for the scan's reach
            gn = _ground_normals(ground, np.asarray(p.points, np.float64))
            edge, _ = view.to_display(ground + gn * (p.width / 2.0), lift)
            half = np.linalg.norm(edge - pts, axis=1)
            reach = np.where(np.isfinite(half), 2.0 * half + 3.0, 0.0)
            o, ok = _scan(fisheye_labels, view, pts, normals, L.guide_paint(p.index), reach)
            scans += len(pts)
            seen, _ = display_to_ground(view, pts[ok] + o[ok, None] * normals[ok], lift)
            offs.append(o[ok])
            grounds.append(ground[ok])
            metres.append(np.copysign(np.linalg.norm(seen - ground[ok], axis=1), o[ok]))
        out.append(LineCheck(p.name, p.kind, p.steering_deg,
                             np.concatenate(offs) if offs else np.empty(0),
                             np.concatenate(grounds) if grounds else np.empty((0, 2)), scans,
                             np.concatenate(metres) if metres else np.empty(0)))
    return out


def _ground_normals(ground: np.ndarray, polyline: np.ndarray) -> np.ndarray:
    """Unit normals (on the ground) of ``polyline`` at its nearest vertex to each point."""
    d = np.gradient(polyline, axis=0)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    near = np.argmin(np.linalg.norm(ground[:, None, :] - polyline[None], axis=2), axis=1)
    return np.column_stack([-d[near, 1], d[near, 0]])


def check_angles(range_deg: float) -> tuple[float, ...]:
    """The steering-wheel angles the check paints: 0, ±50 % and ±100 % of the range."""
    return (0.0, 0.5 * range_deg, -0.5 * range_deg, range_deg, -range_deg)


def check_guidelines(scene: Scene, params: IspParams, output: OutputSpec, *,
                     steering_deg: Sequence[float] | None = None, scale: float = 1.0,
                     render: Callable[[Scene, float], np.ndarray] | None = None,
                     progress: bool = False) -> GuidelineCheck:
    """Check the scene's guidelines through the renderer (see the module docstring).

    Parameters
    ----------
    scene : Scene
    params : IspParams
        The ISP setting, for the full-size sensor.
    output : OutputSpec
        Its mirroring is used; the size is the image of record's.
    steering_deg : sequence of float, optional
        Steering-wheel angles whose trajectories are checked (default :func:`check_angles`).
    scale : float
        Render the fisheye at this fraction of the sensor (RAD and shifts follow); the RVM
        image keeps the size of record.
    render : callable, optional
        ``render(scene, scale) -> fisheye labels`` (default: the render cache,
        :func:`rvmsim.render.cached_render`).
    progress : bool
        With the default ``render``: a progress bar over each render.

    Returns
    -------
    GuidelineCheck
    """
    if render is None:
        render = functools.partial(_cached_labels, progress=progress)
    spec = scene_spec(scene)
    gear = running_gear(scene)
    width = scene_vehicle_width(scene)
    angles = check_angles(gear.steering_range_deg) if steering_deg is None else steering_deg
    groups = [static_lines(width, spec)]
    groups += [trajectory_lines(gear, width, spec, float(a)) for a in angles]
    cam = scene.fisheye_camera()
    p = params
    if scale != 1.0:
        cam, p = cam.scaled(scale), params.for_input_scale(scale)
    view = guideline_view(scene, p, output, camera=cam)
    checks: list[LineCheck] = []
    for group in groups:
        if not group:
            continue
        painted = painted_scene(scene, group)
        checks += measure_painted(render(painted, scale), view, painted.test_site.painted_lines)
    return GuidelineCheck(view.output, tuple(checks))


def _cached_labels(scene: Scene, scale: float, *, progress: bool = False) -> np.ndarray:
    return cached_render(scene, scale=scale, progress=progress)[0].labels
