"""The ISP map, exactly: fisheye correction + virtual pan-tilt-zoom (the paper's section IV,
Table 2).

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

Speed: the map is smooth, so the fast map (:mod:`rvmsim.isp.map`) evaluates these formulas
on a coarse grid of nodes and interpolates between them; :func:`build_map_exact` here is the
reference it is measured against.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .params import IspParams, OutputSpec

__all__ = ["IspMap", "build_map_exact", "map_points", "plane_and_view", "pixel_to_ray_matrix",
           "view_rotation", "isp_rays"]


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
        """(H_o, W_o) input u of each output pixel, px (a view of ``xy``)."""
        return self.xy[..., 0]

    @property
    def map_y(self) -> np.ndarray:
        """(H_o, W_o) input v of each output pixel, px (a view of ``xy``)."""
        return self.xy[..., 1]


def plane_and_view(p: IspParams) -> tuple[np.ndarray, np.ndarray]:
    """The two rotations of the map (steps 3 and 4 of the module docstring).

    Returns
    -------
    r_plane : (3, 3) float64
        Tilt of the virtual image plane (Theta about the in-plane axis ⟂ azimuth Phi).
    r_view : (3, 3) float64
        V camera → A camera: Rz(φ_cv)·Ry(θ_cv)·Rz(α_sz − φ_cv).

    Convention
    ----------
    Both camera frames are OpenCV's (x right, y down, z the optical axis).
    """
    return tuple(np.array(m) for m in _plane_and_view_lists(p))  # type: ignore[return-value]


def _plane_and_view_lists(p: IspParams) -> tuple[list[list[float]], list[list[float]]]:
    """:func:`plane_and_view` as nested lists, written out in plain floats (Rodrigues about
    an in-plane axis; the ZYZ product Rz(φ_cv)·Ry(θ_cv)·Rz(α_sz − φ_cv)): this runs for
    every tuning candidate, where numpy's per-call overhead on 3×3 arrays would dominate."""
    phi_st = math.radians(p.phi)
    x, y = -math.sin(phi_st), math.cos(phi_st)  # in-plane axis, ⟂ azimuth φ_st
    c, s = math.cos(math.radians(p.theta)), math.sin(math.radians(p.theta))
    k = 1.0 - c
    r_plane = [[c + x * x * k, x * y * k, s * y],
               [x * y * k, c + y * y * k, -s * x],
               [-s * y, s * x, c]]
    return r_plane, _view_lists(p.h_pan, p.v_pan, p.tilt)


def _view_lists(h_pan: float, v_pan: float, tilt: float) -> list[list[float]]:
    """R_view = Rz(φ_cv)·Ry(θ_cv)·Rz(α_sz − φ_cv) of pans and tilt in degrees, as lists."""
    a, b, g = math.radians(v_pan), math.radians(h_pan), math.radians(tilt - v_pan)
    ca, sa, cb, sb, cg, sg = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(g), math.sin(g)
    return [[ca * cb * cg - sa * sg, -ca * cb * sg - sa * cg, ca * sb],
            [sa * cb * cg + ca * sg, -sa * cb * sg + ca * cg, sa * sb],
            [-sb * cg, sb * sg, cb]]


def view_rotation(h_pan: float, v_pan: float, tilt: float) -> np.ndarray:
    """The V camera → A camera rotation of pans and tilt (degrees; step 4 of the module
    docstring): (3, 3) float64, as :func:`plane_and_view` gives it.

    Convention
    ----------
    Both camera frames are OpenCV's (x right, y down, z the optical axis).
    """
    return np.array(_view_lists(h_pan, v_pan, tilt))


def isp_rays(p: IspParams, uv: np.ndarray, input_size: tuple[int, int]) -> np.ndarray:
    """The rays the ISP's lens (step 5: equidistance, RAD over FOV/2, centred at the input
    image centre moved by the H/V shifts) gives input pixels: (3, N) unit vectors in the A
    camera frame.

    Convention
    ----------
    ``uv`` (N, 2) input px, pixel centres at integer coordinates.
    """
    pts = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    w_in, h_in = input_size
    dx = pts[:, 0] - ((w_in - 1) / 2.0 + p.h_shift)
    dy = pts[:, 1] - ((h_in - 1) / 2.0 + p.v_shift)
    r = np.hypot(dx, dy)
    theta = r / (p.rad / math.radians(p.fov / 2.0))
    s = np.where(r > 0, np.sin(theta) / np.where(r > 0, r, 1.0), 0.0)
    return np.stack([s * dx, s * dy, np.cos(theta)])


def pixel_to_ray_matrix(p: IspParams, out: OutputSpec) -> np.ndarray:
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


def map_points(
    p: IspParams, u: np.ndarray, v: np.ndarray, input_size: tuple[int, int], out: OutputSpec
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The exact map at output pixel coordinates.

    Parameters
    ----------
    p : IspParams
    u, v : ndarray
        Output (RVM) pixel coordinates, px (same shape).
    input_size : (int, int)
        (W_i, H_i) of the fisheye image, px.
    out : OutputSpec

    Returns
    -------
    u_in, v_in : ndarray, float64
        Input (fisheye) pixel coordinates, px.
    in_circle : ndarray of bool
        θ ≤ FOV/2: the ray lies inside the ISP's assumed image circle.

    Convention
    ----------
    Pixel centres at integer coordinates in both images; output → input (dst → src).
    """
    a = pixel_to_ray_matrix(p, out)
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
    """The map evaluated exactly at every output pixel (reference; ~5× slower than
    :func:`build_map`).

    Convention
    ----------
    ``xy[v, u]`` is the input (fisheye) position, px, of output pixel (u, v): dst → src, as
    cv2.remap reads it; pixel centres at integer coordinates.
    """
    u, v = np.meshgrid(np.arange(output.width, dtype=np.float64),
                       np.arange(output.height, dtype=np.float64))
    ux, vy, _ = map_points(params, u, v, input_size, output)
    return IspMap(np.dstack([ux, vy]).astype(np.float32), input_size, output)
