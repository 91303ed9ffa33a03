"""Fold the rendered cube faces into the fisheye image.

Colour is area-averaged: each fisheye pixel is the mean of :data:`AA_TAPS` × :data:`AA_TAPS`
bilinear samples (``cv2.remap``) of the face atlas spread over the pixel's footprint (a box
filter one fisheye pixel wide, through the local Jacobian of the map), so that edge
sharpness does not depend on ``render.oversample``; plain bilinear sampling of a denser
atlas does no low-pass and aliases.  Labels are sampled nearest at the pixel centres, so
label IDs are never blended.

Conventions
-----------
The map is the layout's ``atlas_x``/``atlas_y``: for every fisheye pixel (dst), where it
samples the atlas (src), cv2.remap's direction; pixel centres at integer coordinates in both.
Fisheye pixels outside the lens's field are black and labelled ``VOID``; inside it, pixels
where no geometry is hit (atlas label 0) are ``SKY``.
"""

from __future__ import annotations

import cv2
import numpy as np

from .. import labels as L
from .cube import CubeLayout

__all__ = ["fold", "fold_color", "fold_labels", "nearest_labels"]

#: Samples per axis of the colour image's box filter (one fisheye pixel wide).
AA_TAPS = 3
#: A map step longer than this (atlas px per fisheye px) crosses a seam or the field's edge.
_SEAM_STEP_PX = 16.0


def fold(layout: CubeLayout, color_atlas: np.ndarray, label_atlas: np.ndarray,
         color_filter: str = "area") -> tuple[np.ndarray, np.ndarray]:
    """The fisheye colour and label images from the rendered atlas.

    Parameters
    ----------
    layout : CubeLayout
        The layout the atlas was rendered for (:func:`~rvmsim.render.cube_layout`).
    color_atlas : (rows, cols, 3) uint8
        Rendered colour of the face crops, side by side.
    label_atlas : (rows, cols) uint8
        Rendered label IDs of the same crops; 0 where no geometry is hit.
    color_filter : {"area", "bilinear"}
        How colour is sampled: area-averaged over the pixel's footprint (the default, as
        the scene's ``render.color_filter``; :func:`fold_color` with :data:`AA_TAPS`² taps),
        so that edge sharpness does not depend on the oversample, or one bilinear tap per
        fisheye pixel.

    Returns
    -------
    color : (H, W, 3) uint8
        ``color_atlas`` resampled by ``color_filter``; black outside the lens's field.
    labels : (H, W) uint8
        Nearest sampling (round half up) of ``label_atlas``; ``SKY`` where it is 0 inside the
        field, ``VOID`` outside it.

    Convention
    ----------
    Map direction dst → src (fisheye pixel → atlas), pixel centres at integer coordinates.
    """
    taps = {"bilinear": 1, "area": AA_TAPS}[color_filter]
    return fold_color(layout, color_atlas, taps), fold_labels(layout, label_atlas)


def _step(a: np.ndarray, axis: int) -> np.ndarray:
    """Per-pixel derivative of the map ``a`` along ``axis`` (atlas px per fisheye px): the
    shorter of the forward and backward differences, so a step across a face seam or the
    field's edge is not taken (0 where both are)."""
    d = np.diff(a, axis=axis)
    pad = [(0, 0), (0, 0)]
    pad[axis] = (1, 0)
    back = np.pad(d, pad, mode="edge")
    pad[axis] = (0, 1)
    fwd = np.pad(d, pad, mode="edge")
    out = np.where(np.abs(fwd) < np.abs(back), fwd, back)
    out[np.abs(out) > _SEAM_STEP_PX] = 0.0
    return out


def _crop_limits(layout: CubeLayout) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per fisheye pixel: the atlas x range [lo, hi] and the largest y of its face crop, px."""
    x0 = np.array([c.atlas_x0 for c in layout.crops], np.float32)
    w = np.array([c.width for c in layout.crops], np.float32)
    h = np.array([c.height for c in layout.crops], np.float32)
    k = np.clip(np.searchsorted(x0, layout.atlas_x, side="right") - 1, 0, len(x0) - 1)
    return x0[k], x0[k] + w[k] - 1, h[k] - 1


def fold_color(layout: CubeLayout, color_atlas: np.ndarray, taps: int = AA_TAPS) -> np.ndarray:
    """The fisheye colour image, area-averaged: (H, W, 3) uint8, black outside the field.

    Each pixel is the mean of ``taps``² bilinear samples (1: one tap at its centre) at the offsets
    ((i + ½)/n − ½, (j + ½)/n − ½) fisheye px from its centre, mapped into the atlas by the
    map's local Jacobian and kept inside the pixel's own face crop.

    Convention
    ----------
    Map direction dst → src (fisheye pixel → atlas), pixel centres at integer coordinates.
    """

    ax, ay = layout.atlas_x, layout.atlas_y
    jxx, jxy = _step(ax, 1), _step(ax, 0)
    jyx, jyy = _step(ay, 1), _step(ay, 0)
    lo, hi, ymax = _crop_limits(layout)
    acc = np.zeros((*ax.shape, color_atlas.shape[2]), np.float32)
    offsets = (np.arange(taps, dtype=np.float32) + 0.5) / taps - 0.5
    for oy in offsets:
        for ox in offsets:
            mx = np.clip(ax + jxx * ox + jxy * oy, lo, hi)
            my = np.clip(ay + jyx * ox + jyy * oy, 0.0, ymax)
            acc += cv2.remap(color_atlas, mx, my, cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    color = np.rint(acc * (1.0 / taps**2)).astype(np.uint8)
    color[~layout.in_fov] = 0
    return color


def fold_labels(layout: CubeLayout, label_atlas: np.ndarray) -> np.ndarray:
    """Only the fisheye label image of :func:`fold` (nearest sampling, round half up; ``SKY``
    where the atlas is 0 inside the field, ``VOID`` outside it): (H, W) uint8."""
    labels = nearest_labels(label_atlas, layout.atlas_x, layout.atlas_y)
    labels[~layout.in_fov] = L.VOID
    return labels


def nearest_labels(label_atlas: np.ndarray, atlas_x: np.ndarray, atlas_y: np.ndarray) -> np.ndarray:
    """The atlas labels nearest to atlas coordinates of any shape (round half up, clipped to
    the atlas), ``SKY`` where the atlas is 0 (no geometry): uint8 of the coordinates' shape.

    Convention
    ----------
    Pixel centres at integer coordinates.
    """
    ix = np.floor(atlas_x + 0.5).astype(np.intp)
    iy = np.floor(atlas_y + 0.5).astype(np.intp)
    np.clip(ix, 0, label_atlas.shape[1] - 1, out=ix)
    np.clip(iy, 0, label_atlas.shape[0] - 1, out=iy)
    labels = label_atlas[iy, ix]
    return np.where(labels == 0, L.SKY, labels).astype(np.uint8)
