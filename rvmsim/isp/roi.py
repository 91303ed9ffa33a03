"""The region of interest: the part of the fisheye image an RVM view uses (the paper's
Table 3 outlines it green), and where fisheye pixels land in the RVM image.

Conventions: pixel centres at integer coordinates (OpenCV) in both images; the ISP map runs
output → input (:mod:`rvmsim.isp.map`), :func:`input_to_output` is its inverse.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .exact import map_points, plane_and_view
from .params import IspParams, OutputSpec

__all__ = ["roi_outline", "draw_roi", "input_to_output", "input_to_plane"]


def input_to_plane(
    params: IspParams, points: np.ndarray, input_size: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """Where fisheye pixels land on the virtual image plane, before the advanced shifts and
    scales (the (x_p, y_p) of :mod:`rvmsim.isp.exact`'s step 2).

    Parameters
    ----------
    params : IspParams
        Only FOV, RAD, the H/V shifts, the pans, zoom, tilt, Theta and Phi matter.
    points : (N, 2) float
        Input (fisheye) pixel coordinates (u, v), px.
    input_size : (int, int)
        (W_i, H_i) of the fisheye image, px.

    Returns
    -------
    xy : (N, 2) float64
        Plane coordinates (x_p, y_p) in output half-widths, not mirrored: an output pixel
        shows plane point ``(x_n / adv_h_scale + adv_h_shift, y_n / adv_v_scale +
        adv_v_shift)``.
    valid : (N,) bool
        False where the ray misses the virtual image plane (behind it).

    Convention
    ----------
    Input → output (src → dst); pixel centres at integer coordinates.
    """
    p = params
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    w_in, h_in = input_size
    dx = pts[:, 0] - ((w_in - 1) / 2.0 + p.h_shift)
    dy = pts[:, 1] - ((h_in - 1) / 2.0 + p.v_shift)
    r = np.hypot(dx, dy)
    theta = r / (p.rad / math.radians(p.fov / 2.0))
    safe = np.where(r > 0, r, 1.0)
    if p.h_pan == p.tilt == p.theta == 0.0:  # both rotations are the identity (the
        # paper's setting; any v_pan and phi then rotate nothing): the plane point is
        # zoom·tan θ along the ray's azimuth, as the general case below gives
        cos = np.cos(theta)
        valid = cos > 1e-12
        scale = p.zoom * np.sin(theta) / np.where(valid, cos, 1e-12) / safe
        return np.stack([scale * dx, scale * dy], axis=1), valid
    s = np.sin(theta)
    ray = np.stack([np.where(r > 0, s * dx / safe, 0.0), np.where(r > 0, s * dy / safe, 0.0),
                    np.cos(theta)], axis=1)
    r_plane, r_view = plane_and_view(p)
    rv = ray @ r_view  # = (R_view^T · ray) per row
    t = np.array([0.0, 0.0, p.zoom])
    normal = r_plane[:, 2]
    denom = rv @ normal
    lam = (normal @ t) / np.where(np.abs(denom) > 1e-12, denom, 1e-12)
    local = (lam[:, None] * rv - t) @ r_plane  # = R_plane^T (λ·r_v − t)
    return local[:, :2], (lam > 0) & (np.abs(denom) > 1e-12)


def input_to_output(
    params: IspParams,
    points: np.ndarray,
    input_size: tuple[int, int],
    output: OutputSpec = OutputSpec(),
) -> tuple[np.ndarray, np.ndarray]:
    """Where fisheye pixels appear in the RVM image: the inverse of the map.

    Parameters
    ----------
    params : IspParams
    points : (N, 2) float
        Input (fisheye) pixel coordinates (u, v), px.
    input_size : (int, int)
        (W_i, H_i) of the fisheye image, px.
    output : OutputSpec

    Returns
    -------
    uv : (N, 2) float64
        Output (RVM) pixel coordinates, px.
    valid : (N,) bool
        False where the ray misses the virtual image plane (behind it).

    Convention
    ----------
    Input → output (src → dst: the inverse of the map's direction); pixel centres at integer
    coordinates in both images.
    """
    p = params
    local, valid = input_to_plane(p, points, input_size)
    half = output.width / 2.0
    xn = (local[:, 0] - p.adv_h_shift) * p.adv_h_scale
    yn = (local[:, 1] - p.adv_v_shift) * p.adv_v_scale
    if output.mirror:
        xn = -xn
    uv = np.stack([xn * half + (output.width - 1) / 2.0, yn * half + (output.height - 1) / 2.0], 1)
    return uv, valid


def roi_outline(
    params: IspParams, input_size: tuple[int, int], output: OutputSpec = OutputSpec(),
    *, samples_per_side: int = 64,
) -> np.ndarray:
    """The input-image region the RVM image uses, as a closed polygon.

    Parameters
    ----------
    params : IspParams
    input_size : (int, int)
        (W_i, H_i) of the fisheye image, px.
    output : OutputSpec
    samples_per_side : int
        Points per side of the output image.

    Returns
    -------
    (N, 2) float64
        Input (fisheye) px of the output image's border, walked clockwise (as displayed)
        from the top-left corner of the output image.

    Convention
    ----------
    The border is that of the output pixel centres (0 … W_o − 1, 0 … H_o − 1), mapped
    exactly (output → input); pixel centres at integer coordinates.
    """
    w, h = output.width - 1, output.height - 1
    s = np.linspace(0.0, 1.0, samples_per_side, endpoint=False)
    u = np.concatenate([s * w, np.full_like(s, w), (1 - s) * w, np.zeros_like(s)])
    v = np.concatenate([np.zeros_like(s), s * h, np.full_like(s, h), (1 - s) * h])
    ux, vy, _ = map_points(params, u, v, input_size, output)
    return np.stack([ux, vy], axis=1)


def draw_roi(fisheye: np.ndarray, params: IspParams, output: OutputSpec = OutputSpec(),
             *, color: tuple[int, int, int] = (0, 255, 0), thickness: int = 2) -> np.ndarray:
    """A copy of the fisheye colour image with the ROI outline drawn (green, as in the
    paper's Table 3).

    Parameters
    ----------
    fisheye : (H_i, W_i, 3) uint8
    params : IspParams
    output : OutputSpec
    color : (int, int, int)
        Line colour, in the image's channel order.
    thickness : int
        Line width, px.

    Convention
    ----------
    The outline of :func:`roi_outline`, drawn anti-aliased at 1/16 px precision.
    """

    img = np.ascontiguousarray(fisheye.copy())
    poly = roi_outline(params, (img.shape[1], img.shape[0]), output)
    if len(poly) >= 2:
        pts = np.round(poly * 16).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(img, [pts], True, color, thickness, cv2.LINE_AA, shift=4)
    return img
