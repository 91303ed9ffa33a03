"""Closed-form sub-solves: the parameters that one EC each pins, set per candidate (the
paper's future work 3, dimension reduction).

Three of the paper's ECs each depend, for a given view, on one of the advanced parameters
alone, because the advanced shifts and scales move and stretch the RVM image as a whole
(:mod:`rvmsim.isp.exact`, step 2: an output pixel shows the virtual-plane point
``(x_n / adv_h_scale + adv_h_shift, y_n / adv_v_scale + adv_v_shift)``):

- **4-1** (board aspect w/h) scales with ``adv_h_scale`` for a given ``adv_v_scale``;
- **3-1** (guideline 2's centre offset) is zero when ``adv_h_shift`` is the plane x of the
  middle of guideline 2;
- **3-2** (guideline 3's height) is linear in ``adv_v_shift``.

:class:`EcSolver` maps the fisheye pixels of the board and the two guidelines onto the
virtual plane once per candidate (:func:`rvmsim.isp.input_to_plane`: a few hundred points)
and sets those parameters so that each EC lands in the middle of its acceptable range (3-1:
offset 0).  The search then has three dimensions fewer (:class:`~rvmsim.tune.CmaEsSolved`).

A solve applies only where it is sound: its EC is the built-in one, enabled, with a range
that has a middle; the parameter is tuned; and the object is in the fisheye image.  A solved
value is clipped to the parameter's search range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import labels as L
from ..criteria import Criteria, builtin_ecs
from ..isp import IspParams, OutputSpec, input_to_plane
from ..search.space import SearchSpace

__all__ = ["EcSolver", "SOLVED_PARAMS"]

#: EC id → the parameter its sub-solve sets.
SOLVED_PARAMS = {"4-1": "adv_h_scale", "3-1": "adv_h_shift", "3-2": "adv_v_shift"}
_LABEL = {"4-1": L.BOARD, "3-1": L.guide_cross(2), "3-2": L.guide_cross(3)}
_MAX_POINTS = 1500


def _outline_points(labels: np.ndarray, label: int) -> np.ndarray:
    """Fisheye px (u, v) of the outline of ``label``'s pixels (every region), at most
    :data:`_MAX_POINTS` (evenly thinned): the extremes of a region's image lie on it.

    Convention
    ----------
    The corners of the outline's pixels (centre ± 0.5 px), so that the points bound the
    region's area, whose image the nearest-neighbour remap samples."""
    import cv2

    mask = (labels == label).astype(np.uint8)
    if not mask.any():
        return np.zeros((0, 2))
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    pts = np.concatenate([c.reshape(-1, 2) for c in contours]).astype(np.float64)
    pts = (pts[:, None, :] + np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
           ).reshape(-1, 2)
    pts = np.unique(pts, axis=0)
    if len(pts) > _MAX_POINTS:
        pts = pts[np.linspace(0, len(pts) - 1, _MAX_POINTS).astype(int)]
    return pts


@dataclass(frozen=True)
class _Solve:
    ec: str
    param: str
    target: float
    points: np.ndarray  # fisheye px (N, 2)
    low: float
    high: float


class EcSolver:
    """Sets, per candidate, the parameters that the board and guideline ECs pin.

    Parameters
    ----------
    fisheye_labels : (H_i, W_i) uint8
        The scene's fisheye label image.
    output : OutputSpec
        The RVM image the ECs are measured on.
    criteria : Criteria
    space : SearchSpace
        The tuned parameters: a solve sets only a tuned parameter, within its range.

    Attributes
    ----------
    names : tuple of str
        The parameters this solver sets (in the order they are solved).
    targets : dict
        EC id → the value its solve aims at.

    Picklable (it goes to tuning's worker processes with the evaluator).
    """

    def __init__(self, fisheye_labels: np.ndarray, output: OutputSpec, criteria: Criteria,
                 space: SearchSpace):
        self.input_size = (fisheye_labels.shape[1], fisheye_labels.shape[0])
        self.output = output
        builtin = {d.id: d for d in builtin_ecs()}
        ranges = {r.name: r for r in space.ranges}
        chosen = {d.id: d for d in criteria.ecs}
        solves = []
        for ec, param in SOLVED_PARAMS.items():
            c = criteria.items.get(ec)
            if (c is None or not c.enabled or chosen[ec] != builtin[ec] or param not in ranges
                    or c.high is None or (ec != "3-1" and c.low is None)):
                continue
            target = 0.0 if ec == "3-1" else (c.low + c.high) / 2.0  # type: ignore[operator]
            if ec == "3-1" and c.low is not None and c.low > 0:
                continue
            pts = _outline_points(fisheye_labels, _LABEL[ec])
            if len(pts) >= 3:
                r = ranges[param]
                solves.append(_Solve(ec, param, target, pts, r.low, r.high))
        self._solves = {s.ec: s for s in solves}
        # every solve's points in one array, mapped in one call per candidate
        self._points = (np.concatenate([s.points for s in solves]) if solves
                        else np.zeros((0, 2)))
        ends = np.cumsum([0] + [len(s.points) for s in solves])
        self._slices = {s.ec: slice(int(a), int(b)) for s, a, b in zip(solves, ends, ends[1:])}
        self.names = tuple(s.param for s in solves)
        self.targets = {s.ec: s.target for s in solves}

    def __call__(self, params: IspParams) -> IspParams:
        """``params`` with the solved parameters set (the others unchanged)."""
        if not self._solves:
            return params
        planes: dict[str, np.ndarray] = {}
        xy_all, ok_all = input_to_plane(params, self._points, self.input_size)
        for ec, part in self._slices.items():
            xy, ok = xy_all[part], ok_all[part]
            if np.count_nonzero(ok) >= 3:
                planes[ec] = xy[ok]
        half = self.output.width / 2.0
        w, h = self.output.width, self.output.height
        v = {n: getattr(params, n) for n in ("adv_h_scale", "adv_h_shift", "adv_v_shift")}
        s_v = params.adv_v_scale
        if "4-1" in planes and "4-1" in self._solves:
            # box of w×h px: w = Δx_p·s_h·half + 1, h = Δy_p·s_v·half + 1; aim w/h = target
            xy = planes["4-1"]
            dx, dy = float(np.ptp(xy[:, 0])), float(np.ptp(xy[:, 1]))
            if dx > 0:
                bh = dy * s_v * half + 1.0
                v["adv_h_scale"] = self._clip("4-1", (self.targets["4-1"] * bh - 1.0) / (dx * half))
        for _ in range(2):  # the guides' visible parts depend on each other's shift: iterate
            if "3-2" in planes and "3-2" in self._solves:
                y = self._guide_row(planes["3-2"], v, half, w)
                if y is not None:
                    row = self.targets["3-2"] / 100.0 * h - 0.5  # the EC: 100·(y + 0.5)/H
                    v["adv_v_shift"] = self._clip("3-2", y - (row - (h - 1) / 2.0) / (s_v * half))
            if "3-1" in planes and "3-1" in self._solves:
                xy = planes["3-1"]
                yv = (xy[:, 1] - v["adv_v_shift"]) * s_v * half + (h - 1) / 2.0
                seen = xy[(yv >= -0.5) & (yv <= h - 0.5), 0]
                if len(seen):
                    v["adv_h_shift"] = self._clip("3-1", (float(seen.min()) + float(seen.max())) / 2)
        return params.replace(**{n: v[n] for n in self.names})

    def _clip(self, ec: str, value: float) -> float:
        s = self._solves[ec]
        return float(min(max(value, s.low), s.high))

    @staticmethod
    def _guide_row(xy: np.ndarray, v: dict[str, float], half: float, w: int) -> float | None:
        """Plane y of a guideline's middle as EC 3-2 measures it: the mean of its pixels
        in the columns at the middle of its visible width."""
        u = (xy[:, 0] - v["adv_h_shift"]) * v["adv_h_scale"] * half + (w - 1) / 2.0
        seen = (u >= -0.5) & (u <= w - 0.5)
        if not seen.any():
            return None
        uc = (float(u[seen].min()) + float(u[seen].max())) / 2.0
        near = seen & (np.abs(u - uc) <= 1.5)
        if not near.any():
            near = seen & (np.abs(u - uc) <= np.sort(np.abs(u[seen] - uc))[min(7, seen.sum() - 1)])
        return float(xy[near, 1].mean())
