"""Closed-form sub-solves (:class:`~rvmsim.criteria.SubSolve`): the outline points they map,
and the solves of the paper's ECs 4-1, 3-1 and 3-2 (the paper's future work 3, dimension
reduction), which :mod:`rvmsim.criteria.builtin` attaches to those ECs.

Three of the paper's ECs each depend, for a given view, on one of the advanced parameters
alone, because the advanced shifts and scales move and stretch the RVM image as a whole
(:mod:`rvmsim.isp.exact`, step 2: an output pixel shows the virtual-plane point
``(x_n / adv_h_scale + adv_h_shift, y_n / adv_v_scale + adv_v_shift)``):

- **board aspect** (4-1, w/h) scales with ``adv_h_scale`` for a given ``adv_v_scale``
  (:func:`board_aspect_scale`);
- **guideline 2's centre offset** (3-1) is zero when ``adv_h_shift`` is the plane x of the
  middle of guideline 2 (:func:`guide_centre_shift`);
- **guideline 3's height** (3-2) is linear in ``adv_v_shift`` (:func:`guide_height_shift`).

Convention
----------
Plane coordinates and pixel centres as in :class:`~rvmsim.criteria.SubSolve`: a W × H RVM
image, ``half = W / 2``; plane x → column ``(x − adv_h_shift) · s_h · half + (W − 1)/2``,
plane y → row ``(y − adv_v_shift) · s_v · half + (H − 1)/2``.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..isp import IspParams, OutputSpec
from .hooks import StackParams

__all__ = ["outline_points", "OUTLINE_MAX_POINTS", "board_aspect_scale", "guide_centre_shift",
           "guide_height_shift", "guide_row", "board_aspect_scale_stack",
           "guide_centre_shift_stack", "guide_height_shift_stack"]

#: At most this many outline points per sub-solve (evenly thinned).
OUTLINE_MAX_POINTS = 1500


def outline_points(labels: np.ndarray, ids: tuple[int, ...]) -> np.ndarray:
    """Fisheye px (u, v) of the outline of the pixels of any of the labels ``ids`` (every
    region), at most :data:`OUTLINE_MAX_POINTS` (evenly thinned): the extremes of a region's
    image lie on it.  (N, 2) float64; (0, 2) when no pixel has those labels.

    Convention
    ----------
    The corners of the outline's pixels (centre ± 0.5 px), so that the points bound the
    region's area, whose image the nearest-neighbour remap samples."""

    hit = (labels == ids[0]) if len(ids) == 1 else np.isin(labels, ids)
    mask = np.asarray(hit, dtype=np.uint8)
    if not mask.any():
        return np.zeros((0, 2))
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    pts = np.concatenate([c.reshape(-1, 2) for c in contours]).astype(np.float64)
    pts = (pts[:, None, :] + np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
           ).reshape(-1, 2)
    pts = np.unique(pts, axis=0)
    if len(pts) > OUTLINE_MAX_POINTS:
        pts = pts[np.linspace(0, len(pts) - 1, OUTLINE_MAX_POINTS).astype(int)]
    return pts


def board_aspect_scale(xy: np.ndarray, params: IspParams, output: OutputSpec,
                       target: float) -> float | None:
    """``adv_h_scale`` that gives the board's bounding box the aspect w/h ``target``.

    A box spanning Δx × Δy on the plane is ``w = Δx · s_h · half + 1`` by
    ``h = Δy · s_v · half + 1`` px; ``w / h = target`` gives s_h.  None when the board has
    no width on the plane."""
    half = output.width / 2.0
    dx, dy = float(np.ptp(xy[:, 0])), float(np.ptp(xy[:, 1]))
    if dx <= 0:
        return None
    bh = dy * params.adv_v_scale * half + 1.0
    return (target * bh - 1.0) / (dx * half)


def guide_centre_shift(xy: np.ndarray, params: IspParams, output: OutputSpec,
                       target: float) -> float | None:
    """``adv_h_shift`` that puts the middle of a guideline's visible rows' extent on the
    image's centre column (``target`` is the offset 0, the only one solved: an offset is
    a distance either side).  None when none of it is in the image's rows."""
    h = output.height
    half = output.width / 2.0
    yv = (xy[:, 1] - params.adv_v_shift) * params.adv_v_scale * half + (h - 1) / 2.0
    seen = xy[(yv >= -0.5) & (yv <= h - 0.5), 0]
    if not len(seen):
        return None
    return (float(seen.min()) + float(seen.max())) / 2


def guide_height_shift(xy: np.ndarray, params: IspParams, output: OutputSpec,
                       target: float) -> float | None:
    """``adv_v_shift`` that puts a guideline's middle (:func:`guide_row`) at ``target`` %
    of the image height (the EC: ``100 · (v + 0.5) / H`` at row v).  None when none of it
    is in the image's columns."""
    w, h = output.width, output.height
    half = w / 2.0
    y = guide_row(xy, params, output)
    if y is None:
        return None
    row = target / 100.0 * h - 0.5
    return y - (row - (h - 1) / 2.0) / (params.adv_v_scale * half)


def guide_row(xy: np.ndarray, params: IspParams, output: OutputSpec) -> float | None:
    """Plane y of a guideline's middle as EC 3-2 measures it: the mean of its outline
    points in the columns at the middle of its visible width (within 1.5 px, else the
    eight nearest); None when none of it is in the image's columns."""
    w = output.width
    half = w / 2.0
    u = (xy[:, 0] - params.adv_h_shift) * params.adv_h_scale * half + (w - 1) / 2.0
    seen = (u >= -0.5) & (u <= w - 0.5)
    if not seen.any():
        return None
    uc = (float(u[seen].min()) + float(u[seen].max())) / 2.0
    near = seen & (np.abs(u - uc) <= 1.5)
    if not near.any():
        near = seen & (np.abs(u - uc) <= np.sort(np.abs(u[seen] - uc))[min(7, seen.sum() - 1)])
    return float(xy[near, 1].mean())


# ---------------------------------------------------------------------------- K images at once
# The solves above on K images' points at once (SubSolve.solve_stack): image k's points are
# xy[starts[k]:starts[k + 1]]; each runs the same floating-point operations on each point
# and each image as its one-image solve, so each image's value is exactly that solve's.
def _per_point(values: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """(K,) per image → (N,) per point."""
    return np.repeat(values, np.diff(starts))


def _extremes(v: np.ndarray, keep: np.ndarray | None, starts: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Per image, the minimum and maximum of ``v`` over its points where ``keep`` (NaN where
    none is kept)."""
    first = starts[:-1]
    if keep is None:
        return np.minimum.reduceat(v, first), np.maximum.reduceat(v, first)
    lo = np.minimum.reduceat(np.where(keep, v, np.inf), first)
    hi = np.maximum.reduceat(np.where(keep, v, -np.inf), first)
    none = np.logical_or.reduceat(keep, first) == 0
    return np.where(none, np.nan, lo), np.where(none, np.nan, hi)


def board_aspect_scale_stack(xy: np.ndarray, starts: np.ndarray, params: StackParams,
                             output: OutputSpec, target: float) -> np.ndarray:
    """:func:`board_aspect_scale` of K images: (K,), NaN where it gives None."""
    half = output.width / 2.0
    x0, x1 = _extremes(xy[:, 0], None, starts)
    y0, y1 = _extremes(xy[:, 1], None, starts)
    dx, dy = x1 - x0, y1 - y0
    bh = dy * params.get("adv_v_scale") * half + 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (target * bh - 1.0) / (dx * half)
    return np.where(dx <= 0, np.nan, out)


def guide_centre_shift_stack(xy: np.ndarray, starts: np.ndarray, params: StackParams,
                             output: OutputSpec, target: float) -> np.ndarray:
    """:func:`guide_centre_shift` of K images: (K,), NaN where it gives None."""
    h = output.height
    half = output.width / 2.0
    shift = _per_point(params.get("adv_v_shift"), starts)
    scale = _per_point(params.get("adv_v_scale"), starts)
    yv = (xy[:, 1] - shift) * scale * half + (h - 1) / 2.0
    lo, hi = _extremes(xy[:, 0], (yv >= -0.5) & (yv <= h - 0.5), starts)
    return (lo + hi) / 2


def guide_height_shift_stack(xy: np.ndarray, starts: np.ndarray, params: StackParams,
                             output: OutputSpec, target: float) -> np.ndarray:
    """:func:`guide_height_shift` of K images: (K,), NaN where it gives None."""
    w, h = output.width, output.height
    half = w / 2.0
    u = ((xy[:, 0] - _per_point(params.get("adv_h_shift"), starts))
         * _per_point(params.get("adv_h_scale"), starts) * half + (w - 1) / 2.0)
    seen = (u >= -0.5) & (u <= w - 0.5)
    lo, hi = _extremes(u, seen, starts)
    uc = (lo + hi) / 2.0
    with np.errstate(invalid="ignore"):
        near = seen & (np.abs(u - _per_point(uc, starts)) <= 1.5)
    y = np.full(len(uc), np.nan)
    for k in range(len(uc)):
        if np.isnan(uc[k]):
            continue
        a, b = starts[k], starts[k + 1]
        nk = near[a:b]
        if not nk.any():  # the eight nearest, as guide_row takes them
            sk, dk = seen[a:b], np.abs(u[a:b] - uc[k])
            nk = sk & (dk <= np.sort(dk[sk])[min(7, sk.sum() - 1)])
        y[k] = float(xy[a:b][nk, 1].mean())
    row = target / 100.0 * h - 0.5
    return y - (row - (h - 1) / 2.0) / (params.get("adv_v_scale") * half)
