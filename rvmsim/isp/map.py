"""The ISP map, fast: the exact formulas (:mod:`rvmsim.isp.exact`) on a coarse grid of nodes,
interpolated bilinearly, with a controlled error; and the remap of the images.

The map is smooth, so :func:`build_map` evaluates the formulas exactly on nodes every
``cell`` output px and interpolates bilinearly with ``cv2.resize``; where the estimated error
exceeds the tolerance the grid is refined, and where even the finest grid is not enough
(a jump in the map) every pixel is evaluated.  The approximation error is measured by
``tools/bench_isp.py`` and bounded in the tests.  This runs for every tuning candidate.

Conventions: pixel centres at integer coordinates (OpenCV); maps are output → input
(cv2.remap's direction), (H_o, W_o, 2) float32 (u, v) of the fisheye image.
"""

from __future__ import annotations

import dataclasses
import math
from collections import OrderedDict
from dataclasses import dataclass
from typing import Protocol

import cv2
import numpy as np

from .. import labels as L
from .exact import IspMap, build_map_exact, pixel_to_ray_matrix
from .params import IspParams, OutputSpec

__all__ = [
    "InputWarp",
    "build_map",
    "map_nodes",
    "MapNodes",
    "RayCache",
    "apply_map",
    "remap_xy",
    "process",
    "DEFAULT_CELL_PX",
    "MIN_CELL_PX",
    "MAP_TOLERANCE_PX",
]


#: Coarsest node spacing (output px) :func:`build_map` tries, and the finest it may refine to.
DEFAULT_CELL_PX = 8
MIN_CELL_PX = 2
#: Largest interpolation error (px) :func:`build_map` accepts, measured at cell centres.
MAP_TOLERANCE_PX = 0.08


def _ray_planes(params: IspParams, output: OutputSpec, cell: int) -> tuple[np.ndarray, np.ndarray]:
    """θ·(P_x, P_y)/ρ at the nodes every ``cell`` px (see :func:`_nodes`): the map before the
    ISP lens' scale f_isp and the image-circle centre, which depend on FOV, RAD and the
    shifts only.  Two (rows, cols) float32 planes.

    Same formulas as :func:`~rvmsim.isp.exact.map_points`, arranged for speed (this runs once or twice per
    tuning candidate): the rays are outer sums of a row and a column term, and θ comes from
    OpenCV's fast ``phase`` (≈ 1e-4 rad) refined by one Newton step, θ += sin(θ_true − θ),
    to ≈ 1e-7 rad (≈ 1e-4 px), a tenth of the time of ``np.arctan2``.
    """

    nx, ny = -(-output.width // cell), -(-output.height // cell)
    ju = (np.arange(nx + 4) - 1.5) * cell - 0.5
    jv = (np.arange(ny + 4) - 1.5) * cell - 0.5
    a = pixel_to_ray_matrix(params, output)
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
    cos_t, sin_t = cv2.polarToCart(None, theta)  # type: ignore[call-overload]  # unit magnitude
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

    def __init__(self, size: int = 256) -> None:
        self.size = size
        # key: the ten ray parameters' values, the output, the cell
        self._entries: OrderedDict[tuple[tuple[float, ...], OutputSpec, int],
                                   tuple[np.ndarray, np.ndarray]] = OrderedDict()

    def planes(self, params: IspParams, output: OutputSpec,
               cell: int) -> tuple[np.ndarray, np.ndarray]:
        """:func:`_ray_planes` of ``params`` at node spacing ``cell``, from the cache when a
        view with the same ten ray parameters and output was seen recently."""
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

    Convention
    ----------
    Output → input (dst → src, cv2.remap's direction); pixel centres at integer coordinates.
    """
    nodes = map_nodes(params, input_size, output, cell=cell, tolerance_px=tolerance_px)
    return IspMap(nodes.window((0, 0, output.width, output.height)), input_size, output)


#: What :meth:`MapNodes.warped` adds to a map's interpolation error, px: a bound on the
#: curvature of the warps it is used for (turns of under a degree, edges moved by a few px)
#: over one cell.
WARP_ERROR_PX = 0.05


class InputWarp(Protocol):
    """A smooth map of the fisheye image onto itself: ``warp(xy)`` → the positions (…, 2)
    the image is read at instead of ``xy`` (…, 2) px (pixel centres at integers)."""

    def __call__(self, xy: np.ndarray) -> np.ndarray: ...


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

    def warped(self, warp: InputWarp) -> MapNodes:
        """These nodes with every input position moved by ``warp`` (a smooth map of the
        fisheye image onto itself, applied after the ISP's: the map then reads the image
        where ``warp`` sends each position).  The interpolation between the moved nodes is
        the map's own, so a window of it holds the warp to within the map's error plus the
        warp's own curvature over a cell (a fraction of a pixel for the small turns and
        shifts it is used for)."""
        def moved(xy: np.ndarray | None) -> np.ndarray | None:
            if xy is None:
                return None
            return np.ascontiguousarray(warp(xy).astype(np.float32))

        return dataclasses.replace(self, grid=moved(self.grid), exact=moved(self.exact),
                                   error_px=self.error_px + WARP_ERROR_PX,
                                   first=None if self.first is None else
                                   self.first.warped(warp))

    def window(self, win: tuple[int, int, int, int]) -> np.ndarray:
        """Map of the output window ``(x0, y0, x1, y1)`` (exclusive ends): (h, w, 2) float32.

        cv2.resize by the factor ``cell`` reads sub-grid node s at destination
        x'' = (s + 0.5)·cell − 0.5, so a sub-grid starting at node ja puts output u at
        x'' = u − (ja − 2)·cell; bilinear weights depend only on x'' mod cell, so every window
        is bit-identical to the same pixels of the whole map.
        """

        x0, y0, x1, y1 = win
        if self.exact is not None:
            return self.exact[y0:y1, x0:x1]
        c = self.cell
        ja = int(math.floor((x0 + 0.5) / c - 0.5)) + 2
        jb = int(math.ceil((x1 - 0.5) / c + 1.5))
        ia = int(math.floor((y0 + 0.5) / c - 0.5)) + 2
        ib = int(math.ceil((y1 - 0.5) / c + 1.5))
        assert self.grid is not None  # no exact map: the grid is set
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
    def planes(c: int) -> tuple[np.ndarray, np.ndarray] | None:
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

    img = np.asarray(image)
    if img.shape[1::-1] != tuple(isp_map.input_size):
        raise ValueError(
            f"image is {img.shape[1]}x{img.shape[0]} px but the map was built for "
            f"{isp_map.input_size[0]}x{isp_map.input_size[1]}"
        )
    if labels is None:
        labels = img.ndim == 2
    interp = cv2.INTER_NEAREST if labels else cv2.INTER_LINEAR
    return remap_xy(img, isp_map.xy, interp, L.VOID)


def remap_xy(image: np.ndarray, xy: np.ndarray, interpolation: int,
             border_value: float | tuple[float, ...]) -> np.ndarray:
    """``cv2.remap`` through a map that holds both coordinates, ``border_value`` outside the
    image.

    Parameters
    ----------
    image : (H_i, W_i[, C]) array
        The image read.
    xy : (H_o, W_o, 2) float32
        Output → input map, (u, v) px (a window of :meth:`MapNodes.window` or
        :attr:`IspMap.xy`).
    interpolation : int
        ``cv2.INTER_NEAREST`` (labels) or ``cv2.INTER_LINEAR``.
    border_value : float or tuple of float
        The value of output pixels whose input lies outside the image (per channel).

    Returns
    -------
    (H_o, W_o[, C]) array, ``image``'s type

    Convention
    ----------
    Pixel centres at integer coordinates (OpenCV).
    """

    # map2 None: xy holds both coordinates (OpenCV 4's stubs do not know that form; 5's do)
    return cv2.remap(image, xy, None, interpolation,  # type: ignore[call-overload, unused-ignore]
                     borderMode=cv2.BORDER_CONSTANT, borderValue=border_value)


def process(
    color: np.ndarray | None,
    labels: np.ndarray | None,
    params: IspParams,
    output: OutputSpec = OutputSpec(),
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Fisheye colour and/or label image → RVM colour and/or label image (one map).

    Parameters
    ----------
    color : (H_i, W_i, 3) uint8 or None
        Fisheye colour image (bilinear sampling).
    labels : (H_i, W_i) uint8 or None
        Fisheye label image (nearest sampling, IDs never blended).
    params : IspParams
    output : OutputSpec

    Returns
    -------
    (color, labels)
        The RVM images, (H_o, W_o[, 3]) uint8, None where none was given; pixels without
        input are 0 (black / ``VOID``).

    Raises
    ------
    ValueError
        When neither image is given.

    Convention
    ----------
    One :func:`build_map` map, output → input, pixel centres at integer coordinates.
    """
    ref = color if color is not None else labels
    if ref is None:
        raise ValueError("give a colour image, a label image or both")
    m = build_map(params, (ref.shape[1], ref.shape[0]), output)
    return (
        None if color is None else apply_map(color, m, labels=False),
        None if labels is None else apply_map(labels, m, labels=True),
    )
