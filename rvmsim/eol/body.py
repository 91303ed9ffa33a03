"""The car's body as its capture shows it: the body's outline found in the capture, and the
body region of the station's label image re-drawn from it.

The station renders the scene at the pose it measured; the test site in that render inherits
the pose error, and so would the body.  But the body moves with the camera's car, and the
capture shows it: the ECs that read the body (the bumper's heights, EC 2-1 to 2-4) are
measured on a body region taken from the capture (:func:`capture_labels`).

Method (:func:`find_body_edge`)
-------------------------------
1. **Predicted outline.** The body's pixels (:data:`rvmsim.labels.BODY_LABELS`) in the
   render at the measured pose that touch a pixel of the scene (not outside the lens), and
   the outline's normal there (toward the scene; the gradient of the body mask smoothed
   with σ = 1.5 px).  The outline itself lies half a pixel out from those pixels' centres.
2. **Found outline.** Along each normal, the capture's colour sampled every pixel within
   ``search_px`` of the predicted outline.  The profile is split in two where two constant
   colours fit it best (least squares; robust to the texture of the ground), and the
   sample at the split, a mix of the two colours, places the edge to a fraction of a pixel
   (a pixel straddling an edge shows the two sides in proportion to its area on each).  A
   split whose two colours differ by less than ``min_contrast`` (RGB, 0–255) is no edge.
3. **Smoothing.** The found offsets are median-filtered over the outline points within
   ``smooth_px``; an offset more than 1.5 px from that median is replaced by it (a speck or a
   reflection does not move the outline).

:func:`capture_labels` then re-draws the body within ``search_px`` of its predicted outline:
a pixel is body where its centre lies inside the found outline (on the body's side of the
tangent at the nearest outline point, moved by that point's offset).

Convention
----------
Fisheye pixels, centres at integer coordinates; offsets along the normal in px, > 0 when the
found outline lies farther out (the body larger) than the predicted one.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial import cKDTree

from .. import labels as L

__all__ = ["BodyEdge", "find_body_edge", "capture_labels", "outline", "SEARCH_PX",
           "MIN_CONTRAST", "SMOOTH_PX"]

#: How far from the predicted outline the capture is searched, px.
SEARCH_PX = 8
#: The smallest difference of the two sides' colours that counts as an edge (RGB distance).
MIN_CONTRAST = 12.0
#: The radius the found offsets are median-filtered over, px.
SMOOTH_PX = 5.0
#: How far outside the two-colour split a body's lip or gap may reach, px.
LIP_PX = 3.0
_OUTLIER_PX = 1.5


@dataclass(frozen=True)
class BodyEdge:
    """The body's outline in the fisheye image.

    Attributes
    ----------
    points : (n, 2) float64
        The outline's predicted points (x, y): the body's outline pixels' centres moved half
        a pixel along the normal.
    normals : (n, 2) float64
        Unit normals there, toward the scene.
    found : (n,) float64
        The found outline's offset along the normal, px (NaN: no edge found).
    offset : (n,) float64
        The offset used (smoothed; the neighbours' median where none was found or trusted).
    """

    points: np.ndarray
    normals: np.ndarray
    found: np.ndarray
    offset: np.ndarray

    def as_dict(self) -> dict[str, object]:
        """JSON-ready summary: outline points, those with an edge found, and the offset of
        the found outline from the predicted one (median, largest), px."""
        off = self.offset
        return {"outline_points": int(off.size), "found": int(np.isfinite(self.found).sum()),
                "offset_median_px": round(float(np.median(off)), 3) if off.size else 0.0,
                "offset_max_px": round(float(np.abs(off).max()), 3) if off.size else 0.0}


def outline(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The body's outline pixels in a label image and their normals (the module
    docstring, step 1): (rows, cols) of the pixels and (n, 2) unit normals (x, y)."""

    body = np.isin(labels, L.BODY_LABELS)
    scene = ~body & (labels != L.VOID)
    near = np.zeros_like(body)
    near[1:] |= scene[:-1]
    near[:-1] |= scene[1:]
    near[:, 1:] |= scene[:, :-1]
    near[:, :-1] |= scene[:, 1:]
    rows, cols = np.nonzero(body & near)
    smooth = cv2.GaussianBlur(body.astype(np.float32), (0, 0), 1.5)
    gy, gx = np.gradient(smooth)
    n = -np.stack([gx[rows, cols], gy[rows, cols]], axis=1)
    norm = np.hypot(n[:, 0], n[:, 1])
    keep = norm > 1e-6
    return rows[keep], cols[keep], n[keep] / norm[keep, None]


def _profiles(image: np.ndarray, points: np.ndarray, normals: np.ndarray,
              steps: np.ndarray) -> np.ndarray:
    """The image sampled (bilinear) at ``points + t·normals`` for every ``t`` of
    ``steps``: (n, len(steps), channels) float32."""

    xy = points[:, None, :] + steps[None, :, None] * normals[:, None, :]
    maps = xy.astype(np.float32)
    img = image.astype(np.float32)
    out = cv2.remap(img, maps[..., 0], maps[..., 1], cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_REPLICATE)
    return out.reshape(len(points), len(steps), -1)


def _split(prof: np.ndarray, steps: np.ndarray, min_contrast: float) -> np.ndarray:
    """Each profile's edge offset (the module docstring, step 2), NaN where there is
    none: profiles (n, m, c) sampled at ``steps`` (m,), body side first."""
    n, m, _ = prof.shape
    cum = np.cumsum(prof, axis=1)
    cum2 = np.cumsum(np.sum(prof ** 2, axis=2), axis=1)
    total, total2 = cum[:, -1], cum2[:, -1]
    j = np.arange(1, m)  # the split before sample j: j samples inside, m − j outside
    s_in, s_out = cum[:, :-1], total[:, None] - cum[:, :-1]
    q_in, q_out = cum2[:, :-1], total2[:, None] - cum2[:, :-1]
    cost = (q_in - np.sum(s_in ** 2, axis=2) / j) + (
        q_out - np.sum(s_out ** 2, axis=2) / (m - j))
    best = np.argmin(cost, axis=1)  # split before sample best + 1
    rows = np.arange(n)
    m_in = s_in[rows, best] / (best + 1)[:, None]
    m_out = s_out[rows, best] / (m - best - 1)[:, None]
    diff = m_in - m_out
    contrast = np.hypot.reduce(diff, axis=1) if diff.shape[1] > 1 else np.abs(diff[:, 0])
    den = np.maximum(np.sum(diff ** 2, axis=1), 1e-9)
    out = np.full(n, np.nan)
    for k in (0, 1):  # the samples either side of the split: their share of the body
        i = best + k
        alpha = np.sum((prof[rows, i] - m_out) * diff, axis=1) / den
        est = steps[i] - 0.5 + alpha
        inside = (alpha > 0.0) & (alpha < 1.0)
        use = np.isnan(out) & inside
        out[use] = est[use]
    out = np.where(np.isnan(out), steps[best] + 0.5, out)  # a clean step: between samples
    out = _outermost(prof, steps, out, s_out[rows, best] / (m - best - 1)[:, None])
    return np.where(contrast >= min_contrast, out, np.nan)


def _outermost(prof: np.ndarray, steps: np.ndarray, split: np.ndarray,
               m_out: np.ndarray) -> np.ndarray:
    """The body's outermost edge near each profile's two-colour split: where, going in
    from the scene, the colour first leaves the scene's by half its largest departure
    within :data:`LIP_PX` outside the split (a dark lip or gap between a bumper's face and
    the ground belongs to the body; the split alone would put the edge at the lip's inner
    side).  Linear between samples; the split where nothing departs."""
    n, m, _ = prof.shape
    beyond = steps[None, :] > split[:, None] + LIP_PX
    ref = m_out.copy()
    has = beyond.sum(axis=1) >= 2
    if has.any():
        scene = np.where(beyond[has][..., None], prof[has], np.nan)
        ref[has] = np.nanmedian(scene, axis=1)
    d = np.hypot.reduce(prof - ref[:, None, :], axis=2) if prof.shape[2] > 1 else np.abs(
        prof[..., 0] - ref[:, None, 0])
    near = (steps[None, :] >= split[:, None] - 1.0) & (steps[None, :] <= split[:, None] + LIP_PX)
    peak = np.where(near, d, 0.0).max(axis=1)
    tau = 0.5 * peak
    out = split.copy()
    # from the outermost sample within LIP_PX of the split inward: the first above tau
    for i in range(m - 1, 0, -1):
        t_in, t_out = steps[i - 1], steps[i]
        d_in, d_out = d[:, i - 1], d[:, i]
        cross = (t_out <= split + LIP_PX) & (d_in >= tau) & (d_out < tau) & (peak > 0) & (
            out == split)
        frac = (d_in - tau) / np.maximum(d_in - d_out, 1e-9)
        out = np.where(cross, t_in + frac * (t_out - t_in), out)
    # a move of less than a pixel is the texture's noise, not a lip
    return np.where(out - split >= 0.75, out, split)


def find_body_edge(capture: np.ndarray, labels: np.ndarray, *, search_px: int = SEARCH_PX,
                   min_contrast: float = MIN_CONTRAST, smooth_px: float = SMOOTH_PX
                   ) -> BodyEdge:
    """The body's outline in ``capture`` near where ``labels`` predict it (the module
    docstring).

    Parameters
    ----------
    capture : (H, W, 3) uint8
        The station's capture, RGB.
    labels : (H, W) uint8
        A label image with the body at about its place (the render at the measured pose).
    search_px : int
        How far along each normal the capture is searched, px.
    min_contrast : float
        The smallest colour difference of the two sides that counts as an edge.
    smooth_px : float
        The radius the offsets are median-filtered over, px.
    """
    rows, cols, normals = outline(labels)
    points = np.stack([cols, rows], axis=1).astype(np.float64) + 0.5 * normals
    if not len(points):
        return BodyEdge(points, normals, np.zeros(0), np.zeros(0))
    steps = np.arange(-search_px, search_px + 1, dtype=np.float64)
    found = _split(_profiles(capture, points, normals, steps), steps, min_contrast)
    return BodyEdge(points, normals, found, _smoothed(points, found, smooth_px))


def _smoothed(points: np.ndarray, found: np.ndarray, radius: float) -> np.ndarray:
    """The offsets used: each the median of the found ones within ``radius``; a found one
    within :data:`_OUTLIER_PX` of that median kept as found."""

    ok = np.isfinite(found)
    if not ok.any():
        return np.zeros(len(found))
    tree = cKDTree(points[ok])
    near = tree.query_ball_point(points, r=radius)
    vals = found[ok]
    fallback = float(np.median(vals))
    med = np.array([float(np.median(vals[idx])) if idx else fallback for idx in near])
    trusted = ok & (np.abs(found - med) <= _OUTLIER_PX)
    return np.where(trusted, found, med)


def capture_labels(labels: np.ndarray, edge: BodyEdge, band_px: int = SEARCH_PX
                   ) -> np.ndarray:
    """``labels`` (the render at the measured pose) with the body re-drawn from ``edge``
    within ``band_px`` of its predicted outline (the module docstring): a pixel turned body
    takes the body label of its nearest outline point, one turned scene the label of the
    scene pixel just outside that point."""
    if not len(edge.points):
        return labels.copy()


    h, w = labels.shape
    pts = edge.points
    tree = cKDTree(pts)
    seeds = np.zeros((h, w), np.uint8)
    px = np.clip(np.rint(pts).astype(int), 0, [w - 1, h - 1])
    seeds[px[:, 1], px[:, 0]] = 1
    band = cv2.dilate(seeds, np.ones((2 * band_px + 3, 2 * band_px + 3), np.uint8))
    by, bx = np.nonzero(band)
    dist, idx = tree.query(np.stack([bx, by], axis=1).astype(np.float64),
                           distance_upper_bound=band_px + 1.0)
    near = np.isfinite(dist)
    sx, sy, idx = bx[near], by[near], idx[near]
    q = np.stack([sx, sy], axis=1).astype(np.float64)
    # signed distance out of the predicted outline along the nearest point's normal: a
    # scene pixel turns body when the found outline lies beyond it, a body pixel scene
    # when the found outline lies inside it (pixels on the wrong side of that tangent, in
    # the outline's corners, keep their label)
    s0 = np.sum((q - pts[idx]) * edge.normals[idx], axis=1)
    off = edge.offset[idx]
    out = labels.copy()
    cur = labels[sy, sx]
    is_body = np.isin(cur, L.BODY_LABELS)
    anchor = np.rint(pts[idx] - 0.5 * edge.normals[idx]).astype(int)
    outer = np.rint(pts[idx] + 1.0 * edge.normals[idx]).astype(int)
    ax, ay = np.clip(anchor[:, 0], 0, w - 1), np.clip(anchor[:, 1], 0, h - 1)
    ox, oy = np.clip(outer[:, 0], 0, w - 1), np.clip(outer[:, 1], 0, h - 1)
    grow = ~is_body & (cur != L.VOID) & (s0 >= 0) & (s0 < off)
    shrink = is_body & (s0 < 0) & (s0 > off)
    out[sy[grow], sx[grow]] = labels[ay[grow], ax[grow]]
    out[sy[shrink], sx[shrink]] = labels[oy[shrink], ox[shrink]]
    return out
