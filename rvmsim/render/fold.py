"""Fold the rendered cube faces into the fisheye image.

Colour is resampled bilinearly (``cv2.remap``) from the face atlas; labels by nearest
sampling of the same coordinates, so label IDs are never blended.

Conventions
-----------
The map is the layout's ``atlas_x``/``atlas_y``: for every fisheye pixel (dst), where it
samples the atlas (src), cv2.remap's direction; pixel centres at integer coordinates in both.
Fisheye pixels outside the lens's field are black and labelled ``VOID``; inside it, pixels
where no geometry is hit (atlas label 0) are ``SKY``.
"""

from __future__ import annotations

import numpy as np

from .. import labels as L
from .cube import CubeLayout

__all__ = ["fold", "fold_labels", "nearest_labels"]


def fold(layout: CubeLayout, color_atlas: np.ndarray,
         label_atlas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The fisheye colour and label images from the rendered atlas.

    Parameters
    ----------
    layout : CubeLayout
        The layout the atlas was rendered for (:func:`~rvmsim.render.cube_layout`).
    color_atlas : (rows, cols, 3) uint8
        Rendered colour of the face crops, side by side.
    label_atlas : (rows, cols) uint8
        Rendered label IDs of the same crops; 0 where no geometry is hit.

    Returns
    -------
    color : (H, W, 3) uint8
        Bilinear resampling of ``color_atlas``; black outside the lens's field.
    labels : (H, W) uint8
        Nearest sampling (round half up) of ``label_atlas``; ``SKY`` where it is 0 inside the
        field, ``VOID`` outside it.

    Convention
    ----------
    Map direction dst → src (fisheye pixel → atlas), pixel centres at integer coordinates.
    """
    import cv2

    color = cv2.remap(
        color_atlas, layout.atlas_x, layout.atlas_y, cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT, borderValue=0,
    )
    color[~layout.in_fov] = 0
    return color, fold_labels(layout, label_atlas)


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
