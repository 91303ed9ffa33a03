"""Edges: Canny edges of two images, their symmetric chamfer distance, and edge overlays.

The comparison runs over the part of the view the scene models (:func:`model_mask`: no
void, no sky), and distances are truncated at :data:`CHAMFER_TRUNCATE_PX` so unmodelled
clutter counts as "far" and not as infinity.

Convention
----------
Images are indexed ``[v, u]`` (row, column); distances are in px between pixel centres.
"""

from __future__ import annotations

import cv2
import numpy as np

from .. import labels as L
from ..pose import grey
from .verdict import EdgeComparison

__all__ = ["CHAMFER_TRUNCATE_PX", "edge_map", "compare_edges", "model_mask", "edge_overlay"]

#: Edge distances above this count as this much in the chamfer mean, px.
CHAMFER_TRUNCATE_PX = 10.0


def edge_map(rgb: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Canny edges of an RGB image inside ``mask``.

    The grey levels are stretched so the 2nd..98th percentiles inside ``mask`` span 0..255,
    blurred with σ = 1 px, and run through Canny (thresholds 40 / 100, L2 gradient).

    Parameters
    ----------
    rgb : (H, W, 3) uint8
    mask : (H, W) bool

    Returns
    -------
    (H, W) bool
    """

    g = grey(rgb)
    vals = g[mask]
    lo, hi = (np.percentile(vals, (2, 98)) if vals.size else (0.0, 255.0))
    g8 = np.clip((g - lo) * (255.0 / max(hi - lo, 1.0)), 0, 255).astype(np.uint8)
    g8 = cv2.GaussianBlur(g8, (0, 0), 1.0)
    e = cv2.Canny(g8, 40, 100, L2gradient=True) > 0
    return np.asarray(e & mask)


def compare_edges(a: np.ndarray, b: np.ndarray,
                  mask: np.ndarray) -> tuple[EdgeComparison, np.ndarray, np.ndarray]:
    """Symmetric chamfer distance between the Canny edges of two RGB images over ``mask``.

    Parameters
    ----------
    a, b : (H, W, 3) uint8
        The images (a: the capture, b: the synthetic frame, by convention).
    mask : (H, W) bool
        Where to compare.

    Returns
    -------
    comparison : EdgeComparison
        Distances in px, each truncated at :data:`CHAMFER_TRUNCATE_PX`.
    edges_a, edges_b : (H, W) bool
        The edge maps, for drawing.
    """

    ea, eb = edge_map(a, mask), edge_map(b, mask)

    def dist_to(e: np.ndarray) -> np.ndarray:
        if not e.any():
            return np.full(e.shape, CHAMFER_TRUNCATE_PX, np.float32)
        return np.asarray(cv2.distanceTransform((~e).astype(np.uint8), cv2.DIST_L2,
                                                cv2.DIST_MASK_PRECISE))

    da, db = dist_to(ea), dist_to(eb)
    ab = np.minimum(db[ea], CHAMFER_TRUNCATE_PX)
    ba = np.minimum(da[eb], CHAMFER_TRUNCATE_PX)
    m_ab = float(ab.mean()) if ab.size else CHAMFER_TRUNCATE_PX
    m_ba = float(ba.mean()) if ba.size else CHAMFER_TRUNCATE_PX
    within = (np.count_nonzero(ab <= 2.0) + np.count_nonzero(ba <= 2.0)) / max(1, ab.size + ba.size)
    return (EdgeComparison((m_ab + m_ba) / 2, m_ab, m_ba, float(within), int(ab.size),
                           int(ba.size)), ea, eb)


def model_mask(labels: np.ndarray) -> np.ndarray:
    """Where the scene models the world: not void, not sky, eroded by 4 px.

    Parameters
    ----------
    labels : (H, W) uint8
        A label image (fisheye or RVM).

    Returns
    -------
    (H, W) bool
    """

    m = ((labels != L.VOID) & (labels != L.SKY)).astype(np.uint8)
    return np.asarray(cv2.erode(m, np.ones((9, 9), np.uint8)) > 0)


def edge_overlay(capture: np.ndarray, e_cap: np.ndarray, e_syn: np.ndarray) -> np.ndarray:
    """The capture dimmed to 45 % grey, its edges green, the scene's magenta, both white.

    Parameters
    ----------
    capture : (H, W, 3) uint8
    e_cap, e_syn : (H, W) bool
        Edge maps of the capture and of the synthetic frame.

    Returns
    -------
    (H, W, 3) uint8 RGB
    """
    g = (grey(capture) * 0.45).astype(np.uint8)
    out = np.repeat(g[..., None], 3, axis=2)
    out[e_cap] = (40, 230, 40)
    out[e_syn] = (255, 40, 255)
    out[e_cap & e_syn] = (255, 255, 255)
    return out
