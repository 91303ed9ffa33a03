"""ISP model: fisheye correction + virtual pan-tilt-zoom (the paper's section IV, Table 2).

The ISP turns the fisheye image of the actual camera (A camera) into the RVM image of a
virtual camera (V camera).  One parameter set is one ``cv2.remap`` map; the colour image is
sampled bilinearly, the label image nearest (IDs are never blended).  The math, step by
step, is in ``docs/isp-model.md``; in short, for an output pixel (u, v) of a W_o × H_o image:

1. normalised output coordinates, square pixels, half-width 1 (mirrored if ``mirror``)::

       x_n = ±(u − (W_o − 1)/2) / (W_o/2),   y_n = (v − (H_o − 1)/2) / (W_o/2)

2. Advanced shift/scale move and stretch them (scale > 1 enlarges along that axis)::

       x_p = x_n / adv_h_scale + adv_h_shift,   y_p = y_n / adv_v_scale + adv_v_shift

3. the point on the virtual image plane: the plane's own tilt (Theta = θ_st about the
   in-plane axis perpendicular to azimuth Phi = φ_st), at distance Zoom on the V camera axis::

       P_v = R_axis(φ_st + 90°, θ_st) · (x_p, y_p, 0) + (0, 0, Zoom)

4. into the A camera: roll by Tilt (α_sz) about the V axis, then turn the V axis away from the
   A axis by H pan (θ_cv, polar angle) toward azimuth V pan (φ_cv; 0 = image right, 90 =
   image down)::

       P_a = Rz(φ_cv) · Ry(θ_cv) · Rz(−φ_cv) · Rz(α_sz) · P_v

5. the ISP's lens model: equidistance with its image circle of radius RAD px spanning FOV
   degrees, centred at the input image centre moved by (H shift, V shift) px::

       θ = atan2(|P_a,xy|, P_a,z),  φ = atan2(P_a,y, P_a,x),  f_isp = RAD / (FOV/2 in rad)
       u_in = (W_i − 1)/2 + h_shift + f_isp·θ·cos φ
       v_in = (H_i − 1)/2 + v_shift + f_isp·θ·sin φ

   The ISP reads the input wherever this lands (FOV and RAD only set the scale f_isp);
   output pixels whose input lies outside the fisheye image are black / ``VOID``.

Conventions: pixel centres at integer coordinates (OpenCV); maps are output → input
(cv2.remap's direction); angles in degrees at the interface, radians inside.

Speed: the map is smooth, so :func:`build_map` evaluates the formulas exactly on a coarse
grid of nodes (every ``cell`` px) and interpolates bilinearly with ``cv2.resize``; the
approximation error is measured by ``tools/bench_isp.py`` and bounded in the tests.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import labels as L
from ..errors import RvmsimError

__all__ = [
    "IspParams",
    "OutputSpec",
    "ParamSpec",
    "PARAM_SPECS",
    "TUNED_BY_DEFAULT",
    "IspMap",
    "build_map",
    "build_map_exact",
    "map_nodes",
    "MapNodes",
    "RayCache",
    "apply_map",
    "process",
    "roi_outline",
    "draw_roi",
    "input_to_output",
    "load_params",
    "params_to_dict",
]


@dataclass(frozen=True)
class ParamSpec:
    """One ISP parameter: its name here, the paper's name and symbol, default, range, unit."""

    name: str
    paper_name: str
    symbol: str
    default: float
    low: float
    high: float
    unit: str
    note: str = ""


#: The 14 parameters of the paper's Table 2.  Where the paper gives no range (FOV, RAD,
#: H/V shift) the range is ours, wide enough for any lens this tool models.
PARAM_SPECS: tuple[ParamSpec, ...] = (
    ParamSpec("fov", "FOV", "FOV", 180.0, 30.0, 240.0, "deg",
              "field of view the ISP assumes for its image circle (range ours)"),
    ParamSpec("rad", "RAD", "RAD", 640.0, 50.0, 2000.0, "px",
              "radius of the ISP's image circle in the input image (range ours)"),
    ParamSpec("h_shift", "H shift", "x_is", 0.0, -500.0, 500.0, "px",
              "image-circle centre right of the input image centre (range ours)"),
    ParamSpec("v_shift", "V shift", "y_is", 0.0, -500.0, 500.0, "px",
              "image-circle centre below the input image centre (range ours)"),
    ParamSpec("h_pan", "H Pan", "θ_cv", 0.0, 0.0, 180.0, "deg",
              "polar angle between the V camera axis and the A camera axis"),
    ParamSpec("v_pan", "V Pan", "φ_cv", 0.0, -180.0, 180.0, "deg",
              "azimuth toward which the V axis turns (0 image right, 90 image down)"),
    ParamSpec("zoom", "Zoom", "r_cv", 1.0, 0.01, 10.0, "",
              "distance of the virtual image plane (output half-width = 1)"),
    ParamSpec("tilt", "Tilt", "α_sz", 0.0, -180.0, 180.0, "deg",
              "roll of the V camera about its axis"),
    ParamSpec("adv_h_shift", "Advanced H shift", "x_os", 0.0, -1.0, 1.0, "",
              "horizontal move of the view window, in output half-widths"),
    ParamSpec("adv_v_shift", "Advanced V shift", "y_os", 0.0, -1.0, 1.0, "",
              "vertical move of the view window, in output half-widths"),
    ParamSpec("adv_h_scale", "Advanced H scale", "s_ox", 1.0, 0.5, 2.0, "",
              "horizontal magnification (> 1 stretches the image horizontally)"),
    ParamSpec("adv_v_scale", "Advanced V scale", "s_oy", 1.0, 0.5, 2.0, "",
              "vertical magnification (> 1 stretches the image vertically)"),
    ParamSpec("theta", "Theta", "θ_st", 0.0, 0.0, 180.0, "deg",
              "tilt of the virtual image plane"),
    ParamSpec("phi", "Phi", "φ_st", 0.0, -180.0, 180.0, "deg",
              "azimuth of the image-plane tilt (0: about the vertical axis)"),
)
_SPEC = {s.name: s for s in PARAM_SPECS}

#: The paper fixes the five angle parameters to 0 and tunes the other nine.
TUNED_BY_DEFAULT: tuple[str, ...] = (
    "fov", "rad", "h_shift", "v_shift", "zoom",
    "adv_h_shift", "adv_v_shift", "adv_h_scale", "adv_v_scale",
)


@dataclass(frozen=True)
class IspParams:
    """The 14 ISP parameters of the paper's Table 2 (ranges in :data:`PARAM_SPECS`).

    Attributes
    ----------
    fov : float
        FOV, degrees: field of view of the ISP's assumed equidistance image circle.
    rad : float
        RAD, px: radius of that image circle in the input (fisheye) image.
    h_shift, v_shift : float
        H/V shift (x_is, y_is), px: image-circle centre relative to the input image centre.
    h_pan, v_pan : float
        H/V pan (θ_cv, φ_cv), degrees: polar angle and azimuth of the V camera axis.
    zoom : float
        Zoom (r_cv): distance of the virtual image plane; larger enlarges.
    tilt : float
        Tilt (α_sz), degrees: roll of the V camera.
    adv_h_shift, adv_v_shift : float
        Advanced H/V shift (x_os, y_os), in [-1, 1] output half-widths.
    adv_h_scale, adv_v_scale : float
        Advanced H/V scale (s_ox, s_oy), in [0.5, 2]; > 1 enlarges along that axis.
    theta, phi : float
        Theta/Phi (θ_st, φ_st), degrees: tilt of the virtual image plane and its azimuth.
    """

    fov: float = 180.0
    rad: float = 640.0
    h_shift: float = 0.0
    v_shift: float = 0.0
    h_pan: float = 0.0
    v_pan: float = 0.0
    zoom: float = 1.0
    tilt: float = 0.0
    adv_h_shift: float = 0.0
    adv_v_shift: float = 0.0
    adv_h_scale: float = 1.0
    adv_v_scale: float = 1.0
    theta: float = 0.0
    phi: float = 0.0

    def __post_init__(self) -> None:
        for spec in PARAM_SPECS:
            value = getattr(self, spec.name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
                raise ValueError(f"{spec.name}: must be a number, got {value!r}")
            value = float(value)
            if not math.isfinite(value) or not spec.low <= value <= spec.high:
                raise ValueError(
                    f"{spec.name}: {value:g} is outside [{spec.low:g}, {spec.high:g}] {spec.unit}"
                    .rstrip()
                )
            object.__setattr__(self, spec.name, value)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(s.name for s in PARAM_SPECS)

    def replace(self, **changes: float) -> IspParams:
        """A copy with some parameters changed (validated)."""
        return dataclasses.replace(self, **changes)

    def for_input_scale(self, factor: float) -> IspParams:
        """The same view on a fisheye image resampled by ``factor`` (e.g. a 0.25 preview
        render): RAD and the H/V shifts are in input px, so they scale with it."""
        return self.replace(rad=self.rad * factor, h_shift=self.h_shift * factor,
                            v_shift=self.v_shift * factor)

    def as_array(self, names: tuple[str, ...] | None = None) -> np.ndarray:
        """Parameter values in the order of ``names`` (default: all 14)."""
        return np.array([getattr(self, n) for n in (names or self.names())], dtype=np.float64)


@dataclass(frozen=True)
class OutputSpec:
    """The RVM image: size in px and whether it is mirrored (RVM displays usually are)."""

    width: int = 1280
    height: int = 720
    mirror: bool = True

    def __post_init__(self) -> None:
        if not (16 <= self.width <= 8192 and 16 <= self.height <= 8192):
            raise ValueError(f"output size must be 16..8192 px, got {self.width}x{self.height}")


@dataclass(frozen=True)
class IspMap:
    """A cv2.remap map from the RVM image to the fisheye image.

    Attributes
    ----------
    xy : (H_o, W_o, 2) float32
        Input (fisheye) pixel coordinates (u, v) of each output pixel (cv2.remap's
        dst → src), possibly a strided view.
    input_size : (int, int)
        (W_i, H_i) of the fisheye image the map reads.
    output : OutputSpec
        The output the map was built for.
    """

    xy: np.ndarray
    input_size: tuple[int, int]
    output: OutputSpec = field(default_factory=OutputSpec)

    @property
    def map_x(self) -> np.ndarray:
        return self.xy[..., 0]

    @property
    def map_y(self) -> np.ndarray:
        return self.xy[..., 1]


# ---------------------------------------------------------------------------- the math
def _plane_and_view(p: IspParams) -> tuple[np.ndarray, np.ndarray]:
    """(R_plane, R_view): image-plane tilt and V→A camera rotation."""
    return tuple(np.array(m) for m in _plane_and_view_lists(p))  # type: ignore[return-value]


def _plane_and_view_lists(p: IspParams) -> tuple[list[list[float]], list[list[float]]]:
    """:func:`_plane_and_view` as nested lists, written out in plain floats (Rodrigues about
    an in-plane axis; the ZYZ product Rz(φ_cv)·Ry(θ_cv)·Rz(α_sz − φ_cv)): this runs for
    every tuning candidate, where numpy's per-call overhead on 3×3 arrays would dominate."""
    phi_st = math.radians(p.phi)
    x, y = -math.sin(phi_st), math.cos(phi_st)  # in-plane axis, ⟂ azimuth φ_st
    c, s = math.cos(math.radians(p.theta)), math.sin(math.radians(p.theta))
    k = 1.0 - c
    r_plane = [[c + x * x * k, x * y * k, s * y],
               [x * y * k, c + y * y * k, -s * x],
               [-s * y, s * x, c]]
    a, b, g = math.radians(p.v_pan), math.radians(p.h_pan), math.radians(p.tilt - p.v_pan)
    ca, sa, cb, sb, cg, sg = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(g), math.sin(g)
    r_view = [[ca * cb * cg - sa * sg, -ca * cb * sg - sa * cg, ca * sb],
              [sa * cb * cg + ca * sg, -sa * cb * sg + ca * cg, sa * sb],
              [-sb * cg, sb * sg, cb]]
    return r_plane, r_view


def _pixel_to_ray_matrix(p: IspParams, out: OutputSpec) -> np.ndarray:
    """3×3 matrix taking homogeneous output pixel coordinates (u, v, 1) to the ray P_a in the
    A camera frame (steps 1–4 of the module docstring are all affine in (u, v))."""
    half = out.width / 2.0
    sx = (-1.0 if out.mirror else 1.0) / half / p.adv_h_scale
    sy = 1.0 / half / p.adv_v_scale
    # x_p = sx·(u − cu) + x_os ;  y_p = sy·(v − cv) + y_os
    ox = p.adv_h_shift - sx * (out.width - 1) / 2.0
    oy = p.adv_v_shift - sy * (out.height - 1) / 2.0
    rp, rv = _plane_and_view_lists(p)
    rows = []
    for i in range(3):
        m0 = rv[i][0] * rp[0][0] + rv[i][1] * rp[1][0] + rv[i][2] * rp[2][0]
        m1 = rv[i][0] * rp[0][1] + rv[i][1] * rp[1][1] + rv[i][2] * rp[2][1]
        rows.append((m0 * sx, m1 * sy, m0 * ox + m1 * oy + rv[i][2] * p.zoom))
    return np.array(rows)


def _map_points(
    p: IspParams, u: np.ndarray, v: np.ndarray, input_size: tuple[int, int], out: OutputSpec
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact map for output pixel coordinates (u, v): (u_in, v_in, θ ≤ FOV/2)."""
    a = _pixel_to_ray_matrix(p, out)
    ax = a[0, 0] * u + a[0, 1] * v + a[0, 2]
    ay = a[1, 0] * u + a[1, 1] * v + a[1, 2]
    az = a[2, 0] * u + a[2, 1] * v + a[2, 2]
    rho = np.hypot(ax, ay)
    theta = np.arctan2(rho, az)
    f_isp = p.rad / math.radians(p.fov / 2.0)
    # f·θ/ρ; where ρ = 0 (the axis) ax = ay = 0, so any finite scale gives the centre.
    scale = f_isp * theta / np.maximum(rho, 1e-300)
    w_in, h_in = input_size
    u_in = ((w_in - 1) / 2.0 + p.h_shift) + scale * ax
    v_in = ((h_in - 1) / 2.0 + p.v_shift) + scale * ay
    return u_in, v_in, theta <= math.radians(p.fov / 2.0)


def build_map_exact(
    params: IspParams, input_size: tuple[int, int], output: OutputSpec = OutputSpec()
) -> IspMap:
    """The map evaluated exactly at every output pixel (reference; ~5× slower)."""
    u, v = np.meshgrid(np.arange(output.width, dtype=np.float64),
                       np.arange(output.height, dtype=np.float64))
    ux, vy, _ = _map_points(params, u, v, input_size, output)
    return IspMap(np.dstack([ux, vy]).astype(np.float32), input_size, output)


#: Coarsest node spacing (output px) :func:`build_map` tries, and the finest it may refine to.
DEFAULT_CELL_PX = 8
MIN_CELL_PX = 2
#: Largest interpolation error (px) :func:`build_map` accepts, measured at cell centres.
MAP_TOLERANCE_PX = 0.08


def _ray_planes(params: IspParams, output: OutputSpec, cell: int) -> tuple[np.ndarray, np.ndarray]:
    """θ·(P_x, P_y)/ρ at the nodes every ``cell`` px (see :func:`_nodes`): the map before the
    ISP lens' scale f_isp and the image-circle centre, which depend on FOV, RAD and the
    shifts only.  Two (rows, cols) float32 planes.

    Same formulas as :func:`_map_points`, arranged for speed (this runs once or twice per
    tuning candidate): the rays are outer sums of a row and a column term, and θ comes from
    OpenCV's fast ``phase`` (≈ 1e-4 rad) refined by one Newton step, θ += sin(θ_true − θ),
    to ≈ 1e-7 rad (≈ 1e-4 px), a tenth of the time of ``np.arctan2``.
    """
    import cv2

    nx, ny = -(-output.width // cell), -(-output.height // cell)
    ju = (np.arange(nx + 4) - 1.5) * cell - 0.5
    jv = (np.arange(ny + 4) - 1.5) * cell - 0.5
    a = _pixel_to_ray_matrix(params, output)
    # float32 throughout: rays to ~1e-7 relative, positions to ~1e-4 px
    col = (a[:, 0, None] * ju[None, :] + a[:, 2, None]).astype(np.float32)  # (3, cols)
    row = (a[:, 1, None] * jv[None, :]).astype(np.float32)  # (3, rows)
    ax = row[0][:, None] + col[0][None, :]
    ay = row[1][:, None] + col[1][None, :]
    az = row[2][:, None] + col[2][None, :]
    # np.sqrt, not cv2.magnitude: the latter's last bit depends on the arrays' alignment, and
    # the same view must give bit-identical nodes every time (windowed = whole image)
    rho = np.sqrt(ax * ax + ay * ay)
    theta = cv2.phase(az, rho)
    cos_t, sin_t = cv2.polarToCart(None, theta)
    theta += (rho * cos_t - az * sin_t) / np.sqrt(rho * rho + az * az)
    theta /= np.maximum(rho, np.float32(1e-30))
    return theta * ax, theta * ay


def _nodes(
    params: IspParams, input_size: tuple[int, int], output: OutputSpec, cell: int,
    rays: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[int, int, np.ndarray]:
    """Exact map on nodes every ``cell`` px with two rings beyond the image: (nx, ny, grid).

    cv2.resize(…, ×cell, INTER_LINEAR) reads source node j at destination x' = (j + 0.5)·cell
    − 0.5; node j is evaluated at output coordinate u = (j − 1.5)·cell − 0.5, so destination
    x' is output x' − 2·cell, and the crop [2·cell, 2·cell + W) is the output image.
    ``rays``: :func:`_ray_planes` of these parameters, when already known.  ``grid`` is
    (rows, cols, 2) float32.
    """
    import cv2

    nx, ny = -(-output.width // cell), -(-output.height // cell)
    gx, gy = rays if rays is not None else _ray_planes(params, output, cell)
    f_isp = np.float32(params.rad / math.radians(params.fov / 2.0))
    w_in, h_in = input_size
    # (numpy broadcasting over a trailing axis of 2 is slow: add the offsets per plane)
    grid = cv2.merge([gx * f_isp + np.float32((w_in - 1) / 2.0 + params.h_shift),
                      gy * f_isp + np.float32((h_in - 1) / 2.0 + params.v_shift)])
    return nx, ny, grid


#: The parameters the ray planes depend on (all but FOV, RAD and the H/V shifts).
_RAY_PARAMS = ("h_pan", "v_pan", "zoom", "tilt", "adv_h_shift", "adv_v_shift", "adv_h_scale",
               "adv_v_scale", "theta", "phi")


class RayCache:
    """Ray planes of recently seen views (:func:`_ray_planes`), for :func:`map_nodes`.

    Candidates that differ only in FOV, RAD and the H/V shifts share them: the paper's
    coarse grid has 3⁴ such candidates per view.  Keyed by the other ten parameters, the
    output and the cell; holds the ``size`` most recent entries.
    """

    def __init__(self, size: int = 256):
        from collections import OrderedDict

        self.size = size
        self._entries: OrderedDict = OrderedDict()

    def planes(self, params: IspParams, output: OutputSpec, cell: int):
        key = (tuple(getattr(params, n) for n in _RAY_PARAMS), output, cell)
        hit = self._entries.get(key)
        if hit is not None:
            self._entries.move_to_end(key)
            return hit
        planes = _ray_planes(params, output, cell)
        self._entries[key] = planes
        if len(self._entries) > self.size:
            self._entries.popitem(last=False)
        return planes


_SECOND_DIFF = (np.array([[1.0, -2.0, 1.0]], np.float32), np.array([[1.0], [-2.0], [1.0]], np.float32))


def _interpolation_error(grid: np.ndarray, input_size: tuple[int, int]) -> float:
    """Estimated largest error of bilinear interpolation between the nodes, px.

    At a cell centre, bilinear interpolation is off by h²/8·(f_uu + f_vv) + O(h⁴); the second
    differences of the node values are h²·f_uu and h²·f_vv, so
    (|Δ²_u f| + |Δ²_v f|) / 8 bounds the error without evaluating anything new.  Only nodes
    whose map lands in (or near) the input image count.  ``grid`` is (rows, cols, 2) float32.
    """
    import cv2

    w, h = input_size
    g = np.ascontiguousarray(grid, dtype=np.float32)
    d2 = np.abs(cv2.filter2D(g, -1, _SECOND_DIFF[0], borderType=cv2.BORDER_REPLICATE))
    d2 += np.abs(cv2.filter2D(g, -1, _SECOND_DIFF[1], borderType=cv2.BORDER_REPLICATE))
    inside = cv2.inRange(g, (-8.0, -8.0), (w + 8.0, h + 8.0))
    inside[[0, -1], :] = 0  # second differences need both neighbours
    inside[:, [0, -1]] = 0
    # A jump in the map (the antipode of the V axis) shows up as a huge second difference.
    worst = cv2.max(d2[..., 0], d2[..., 1])
    return float(cv2.minMaxLoc(worst, inside)[1]) / 8.0


def build_map(
    params: IspParams,
    input_size: tuple[int, int],
    output: OutputSpec = OutputSpec(),
    *,
    cell: int = DEFAULT_CELL_PX,
    tolerance_px: float = MAP_TOLERANCE_PX,
) -> IspMap:
    """Build the remap map for one parameter set, fast, with a controlled error.

    The formulas are evaluated exactly on nodes every ``cell`` output px (two rings beyond
    the image) and interpolated bilinearly by ``cv2.resize``, whose sample positions coincide
    with the nodes.  The interpolation error is estimated where it peaks, at the cell centres;
    where it exceeds ``tolerance_px`` the grid is refined to 4 or 2 px (see
    :func:`map_nodes`), and where even that is not enough (a jump in the map) every pixel is
    evaluated.  Wide views near the ISP's horizon need the finer grids.

    Parameters
    ----------
    params : IspParams
        The parameter set.
    input_size : (int, int)
        (width, height) of the fisheye image, px.
    output : OutputSpec
        Output size and mirroring.
    cell : int
        Starting node spacing, px.
    tolerance_px : float
        Accepted interpolation error, px (measured at cell centres inside the input image).

    Returns
    -------
    IspMap
        ``map_x``/``map_y`` may be non-contiguous views of one buffer (cv2 accepts them).
    """
    nodes = map_nodes(params, input_size, output, cell=cell, tolerance_px=tolerance_px)
    return IspMap(nodes.window((0, 0, output.width, output.height)), input_size, output)


@dataclass(frozen=True)
class MapNodes:
    """The exactly evaluated nodes of a map, from which any window of it is interpolated.

    ``grid`` (rows, cols, 2) float32 holds node j at output coordinate (j − 1.5)·cell − 0.5
    (two rings beyond the image).  ``exact`` holds the whole map instead when no node grid
    was fine enough.  ``error_px`` is the estimated interpolation error; ``first`` is the
    coarser grid tried first when this one is a refinement (cheap for callers that only
    need the map to within its error, like the evaluator's windows).
    """

    grid: np.ndarray | None
    cell: int
    exact: np.ndarray | None = None
    error_px: float = 0.0
    first: MapNodes | None = None

    def window(self, win: tuple[int, int, int, int]) -> np.ndarray:
        """Map of the output window ``(x0, y0, x1, y1)`` (exclusive ends): (h, w, 2) float32.

        cv2.resize by the factor ``cell`` reads sub-grid node s at destination
        x'' = (s + 0.5)·cell − 0.5, so a sub-grid starting at node ja puts output u at
        x'' = u − (ja − 2)·cell; bilinear weights depend only on x'' mod cell, so every window
        is bit-identical to the same pixels of the whole map.
        """
        import cv2

        x0, y0, x1, y1 = win
        if self.exact is not None:
            return self.exact[y0:y1, x0:x1]
        c = self.cell
        ja = int(math.floor((x0 + 0.5) / c - 0.5)) + 2
        jb = int(math.ceil((x1 - 0.5) / c + 1.5))
        ia = int(math.floor((y0 + 0.5) / c - 0.5)) + 2
        ib = int(math.ceil((y1 - 0.5) / c + 1.5))
        sub = self.grid[ia : ib + 1, ja : jb + 1]
        full = cv2.resize(sub, (sub.shape[1] * c, sub.shape[0] * c),
                          interpolation=cv2.INTER_LINEAR)
        ox, oy = x0 - (ja - 2) * c, y0 - (ia - 2) * c
        return full[oy : oy + (y1 - y0), ox : ox + (x1 - x0)]


def map_nodes(
    params: IspParams,
    input_size: tuple[int, int],
    output: OutputSpec = OutputSpec(),
    *,
    cell: int = DEFAULT_CELL_PX,
    tolerance_px: float = MAP_TOLERANCE_PX,
    rays: RayCache | None = None,
) -> MapNodes:
    """The node grid :func:`build_map` interpolates (error-controlled, see there).

    ``rays``: a :class:`RayCache` to reuse the ray planes of views seen before (tuning).

    The error is estimated on the grid at ``cell`` px; bilinear interpolation's error scales
    with the square of the spacing (the estimates at 4 and 2 px agree with this to 0.7 % on
    random views), so the finest grid needed is chosen from that one estimate, with 2 %
    to spare, and only that grid is evaluated besides."""
    def planes(c: int):
        return None if rays is None else rays.planes(params, output, c)

    _, _, grid = _nodes(params, input_size, output, cell, planes(cell))
    error = _interpolation_error(grid, input_size)
    if error <= tolerance_px:
        return MapNodes(grid, cell, error_px=error)
    first = MapNodes(grid, cell, error_px=error)
    fine = cell
    while fine > MIN_CELL_PX and error * (fine / cell) ** 2 * _SCALING_SAFETY > tolerance_px:
        fine = max(MIN_CELL_PX, fine // 2)
    fine_error = error * (fine / cell) ** 2
    if fine_error * _SCALING_SAFETY > tolerance_px:  # no grid is fine enough (a jump in the map)
        return MapNodes(None, fine, build_map_exact(params, input_size, output).xy, first=first)
    _, _, grid = _nodes(params, input_size, output, fine, planes(fine))
    return MapNodes(grid, fine, error_px=fine_error, first=first)


_SCALING_SAFETY = 1.02


def apply_map(image: np.ndarray, isp_map: IspMap, *, labels: bool | None = None) -> np.ndarray:
    """Remap a fisheye image into the RVM image.

    Parameters
    ----------
    image : (H_i, W_i) uint8 or (H_i, W_i, 3) uint8
        Fisheye colour image, or label image.
    isp_map : IspMap
        From :func:`build_map`.
    labels : bool, optional
        Nearest sampling, IDs never blended (default: True for 2-D uint8 input).  Otherwise
        bilinear.  Pixels without input are 0 (black / ``VOID``).

    Returns
    -------
    (H_o, W_o[, 3]) uint8
    """
    import cv2

    img = np.asarray(image)
    if img.shape[1::-1] != tuple(isp_map.input_size):
        raise ValueError(
            f"image is {img.shape[1]}x{img.shape[0]} px but the map was built for "
            f"{isp_map.input_size[0]}x{isp_map.input_size[1]}"
        )
    if labels is None:
        labels = img.ndim == 2
    interp = cv2.INTER_NEAREST if labels else cv2.INTER_LINEAR
    return cv2.remap(img, isp_map.xy, None, interp,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=L.VOID)


def process(
    color: np.ndarray | None,
    labels: np.ndarray | None,
    params: IspParams,
    output: OutputSpec = OutputSpec(),
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Fisheye colour and/or label image → RVM colour and/or label image (one map)."""
    ref = color if color is not None else labels
    if ref is None:
        raise ValueError("give a colour image, a label image or both")
    m = build_map(params, (ref.shape[1], ref.shape[0]), output)
    return (
        None if color is None else apply_map(color, m, labels=False),
        None if labels is None else apply_map(labels, m, labels=True),
    )


def input_to_output(
    params: IspParams,
    points: np.ndarray,
    input_size: tuple[int, int],
    output: OutputSpec = OutputSpec(),
) -> tuple[np.ndarray, np.ndarray]:
    """Where fisheye pixels appear in the RVM image: the inverse of the map.

    Parameters
    ----------
    points : (N, 2) float
        Input (fisheye) pixel coordinates (u, v).

    Returns
    -------
    uv : (N, 2) float64
        Output (RVM) pixel coordinates, pixel-centre convention.
    valid : (N,) bool
        False where the ray misses the virtual image plane (behind it).
    """
    p = params
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    w_in, h_in = input_size
    dx = pts[:, 0] - ((w_in - 1) / 2.0 + p.h_shift)
    dy = pts[:, 1] - ((h_in - 1) / 2.0 + p.v_shift)
    r = np.hypot(dx, dy)
    theta = r / (p.rad / math.radians(p.fov / 2.0))
    safe = np.where(r > 0, r, 1.0)
    s = np.sin(theta)
    ray = np.stack([np.where(r > 0, s * dx / safe, 0.0), np.where(r > 0, s * dy / safe, 0.0),
                    np.cos(theta)], axis=1)
    r_plane, r_view = _plane_and_view(p)
    rv = ray @ r_view  # = (R_view^T · ray) per row
    t = np.array([0.0, 0.0, p.zoom])
    normal = r_plane[:, 2]
    denom = rv @ normal
    lam = (normal @ t) / np.where(np.abs(denom) > 1e-12, denom, 1e-12)
    local = (lam[:, None] * rv - t) @ r_plane  # = R_plane^T (λ·r_v − t)
    half = output.width / 2.0
    xn = (local[:, 0] - p.adv_h_shift) * p.adv_h_scale
    yn = (local[:, 1] - p.adv_v_shift) * p.adv_v_scale
    if output.mirror:
        xn = -xn
    uv = np.stack([xn * half + (output.width - 1) / 2.0, yn * half + (output.height - 1) / 2.0], 1)
    return uv, (lam > 0) & (np.abs(denom) > 1e-12)


def roi_outline(
    params: IspParams, input_size: tuple[int, int], output: OutputSpec = OutputSpec(),
    *, samples_per_side: int = 64,
) -> np.ndarray:
    """The input-image region the RVM image uses, as a closed polygon.

    Returns
    -------
    (N, 2) float64
        Input (fisheye) px of the output image's border, walked clockwise (as displayed)
        from the top-left corner of the output image.
    """
    w, h = output.width - 1, output.height - 1
    s = np.linspace(0.0, 1.0, samples_per_side, endpoint=False)
    u = np.concatenate([s * w, np.full_like(s, w), (1 - s) * w, np.zeros_like(s)])
    v = np.concatenate([np.zeros_like(s), s * h, np.full_like(s, h), (1 - s) * h])
    ux, vy, _ = _map_points(params, u, v, input_size, output)
    return np.stack([ux, vy], axis=1)


def draw_roi(fisheye: np.ndarray, params: IspParams, output: OutputSpec = OutputSpec(),
             *, color: tuple[int, int, int] = (0, 255, 0), thickness: int = 2) -> np.ndarray:
    """A copy of the fisheye colour image with the ROI outline drawn (green, as in the
    paper's Table 3)."""
    import cv2

    img = np.ascontiguousarray(fisheye.copy())
    poly = roi_outline(params, (img.shape[1], img.shape[0]), output)
    if len(poly) >= 2:
        pts = np.round(poly * 16).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(img, [pts], True, color, thickness, cv2.LINE_AA, shift=4)
    return img


# ---------------------------------------------------------------------------- files
def params_to_dict(params: IspParams, output: OutputSpec | None = None) -> dict[str, Any]:
    """Plain dict for a params file (the 14 parameters, then ``output``)."""
    d: dict[str, Any] = {n: getattr(params, n) for n in IspParams.names()}
    if output is not None:
        d["output"] = {"size": [output.width, output.height], "mirror": output.mirror}
    return d


def load_params(path: str | Path) -> tuple[IspParams, OutputSpec]:
    """Read a params file (YAML or JSON): any of the 14 parameter names (missing ones take
    the paper's defaults) and an optional ``output: {size: [W, H], mirror: bool}``.

    Raises
    ------
    RvmsimError
        One line naming the file and the key for unreadable files, malformed YAML/JSON,
        unknown keys, non-numbers and values out of range.
    """
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise RvmsimError(f"{path}: params file not found") from None
    except (OSError, UnicodeDecodeError) as err:
        raise RvmsimError(f"{path}: cannot read params file ({err})") from None
    try:
        data = json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
    except (yaml.YAMLError, json.JSONDecodeError) as err:
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise RvmsimError(f"{path}: malformed params file: {first}") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise RvmsimError(f"{path}: a params file must be a mapping (name: value)")
    data = dict(data)
    out_data = data.pop("output", None)
    unknown = sorted(set(data) - set(IspParams.names()))
    if unknown:
        raise RvmsimError(f"{path}: {unknown[0]}: unknown ISP parameter "
                          f"(known: {', '.join(IspParams.names())})")
    for key, value in data.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise RvmsimError(f"{path}: {key}: must be a number, got {value!r}")
        spec = _SPEC[key]
        if not math.isfinite(value) or not spec.low <= value <= spec.high:
            raise RvmsimError(f"{path}: {key}: {value:g} is outside [{spec.low:g}, "
                              f"{spec.high:g}] {spec.unit}".rstrip())
    params = IspParams(**{k: float(v) for k, v in data.items()})
    output = OutputSpec()
    if out_data is not None:
        if not isinstance(out_data, dict) or set(out_data) - {"size", "mirror"}:
            raise RvmsimError(f"{path}: output: expected {{size: [W, H], mirror: true|false}}")
        size = out_data.get("size", [output.width, output.height])
        mirror = out_data.get("mirror", output.mirror)
        if (not isinstance(size, list) or len(size) != 2
                or not all(isinstance(x, int) and not isinstance(x, bool) for x in size)):
            raise RvmsimError(f"{path}: output.size: expected [width, height] in px")
        if not isinstance(mirror, bool):
            raise RvmsimError(f"{path}: output.mirror: expected true or false")
        try:
            output = OutputSpec(size[0], size[1], mirror)
        except ValueError as err:
            raise RvmsimError(f"{path}: output.size: {err}") from None
    return params, output
