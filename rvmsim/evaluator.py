"""Fast per-candidate evaluation for tuning: ISP map → label windows → ECs → EC score.

:func:`rvmsim.criteria.evaluate` needs the whole RVM label image.  Tuning only needs the
eleven measurements, and each looks at one group of labels (F's stripe, the board, …) that
covers a small part of the image.  :class:`CandidateEvaluator` therefore

1. finds, once per scene, boxes around each label group's pixels in the fisheye image (one per
   128-px tile the group touches);
2. per candidate, maps each box's outline through the inverse ISP (:func:`isp.input_to_output`)
   to the window of the RVM image where those pixels can appear (a smooth one-to-one map takes
   a box's outline to the outline of its image), grown by a safety margin;
3. remaps only those windows (plus the bumper's columns) and measures them with exactly the
   code that measures whole images (:func:`criteria.measure_source`).

The result equals ``evaluate(apply_map(labels, build_map(params, …)))`` pixel for pixel; the
tests check this on random candidates.  Where a box's outline leaves the ISP's valid region
(rays behind the virtual image plane) the window falls back to the whole image.
"""

from __future__ import annotations

import numpy as np

from . import labels as L
from .criteria import GROUPS, Criteria, EcResult, LabelSource, Window, default_criteria
from .criteria import measure_source, score
from .isp import IspParams, MapNodes, OutputSpec, _map_points, input_to_output, map_nodes

__all__ = ["CandidateEvaluator"]

#: Output px added around each window: covers the fast map's ≤ 0.1 px error, nearest
#: sampling, and the outline's sagitta between its samples.
WINDOW_MARGIN_PX = 4
#: Fisheye tiles (px) a label group's pixels are boxed in: a group spread over the fisheye
#: image (the garnish around its bottom) becomes several small boxes, not one huge one.
TILE_PX = 128
_SIDE_SAMPLES = 8
#: Block size (fisheye px) of the coarse garnish/trunk occupancy used for EC 2-4.
_BLOCK_PX = 16


def _group_tiles(labels: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Boxes (x, y, w, h) of each group's pixels within each fisheye tile that holds some."""
    import cv2

    names, boxes = [], []
    h, w = labels.shape
    for name, ids in GROUPS.items():
        if name == "upper_body":
            continue  # EC 2-4 has its own test (CandidateEvaluator._no_body_up_there)
        mask = cv2.LUT(labels, L.lut(ids))
        for ty in range(0, h, TILE_PX):
            for tx in range(0, w, TILE_PX):
                x, y, bw, bh = cv2.boundingRect(mask[ty : ty + TILE_PX, tx : tx + TILE_PX])
                if bw:
                    names.append(name)
                    boxes.append((tx + x, ty + y, bw, bh))
    return names, np.asarray(boxes, dtype=np.float64).reshape(-1, 4)


def _outlines(boxes: np.ndarray) -> np.ndarray:
    """(n_boxes · 4·_SIDE_SAMPLES, 2) points around each box grown by one pixel (nearest
    sampling reads up to half a pixel outside what it lands on)."""
    x0 = boxes[:, 0] - 1.0
    y0 = boxes[:, 1] - 1.0
    x1 = boxes[:, 0] + boxes[:, 2]
    y1 = boxes[:, 1] + boxes[:, 3]
    t = np.linspace(0.0, 1.0, _SIDE_SAMPLES, endpoint=False)[None, :]
    xs = np.concatenate([x0[:, None] + t * (x1 - x0)[:, None], np.repeat(x1[:, None], t.size, 1),
                         x1[:, None] - t * (x1 - x0)[:, None], np.repeat(x0[:, None], t.size, 1)], 1)
    ys = np.concatenate([np.repeat(y0[:, None], t.size, 1), y0[:, None] + t * (y1 - y0)[:, None],
                         np.repeat(y1[:, None], t.size, 1), y1[:, None] - t * (y1 - y0)[:, None]], 1)
    return np.stack([xs.ravel(), ys.ravel()], 1)


class _RemapSource(LabelSource):
    def __init__(self, fisheye: np.ndarray, nodes: MapNodes, windows: dict[str, Window],
                 shape: tuple[int, int]):
        self.fisheye = fisheye
        self.nodes = nodes
        self.windows = windows
        self.shape = shape

    def window(self, group: str) -> Window:
        return self.windows[group]

    def pixels(self, win: Window) -> np.ndarray:
        import cv2

        x0, y0, x1, y1 = win
        if x1 <= x0 or y1 <= y0:
            return np.zeros((0, 0), np.uint8)
        return cv2.remap(self.fisheye, self.nodes.window(win), None, cv2.INTER_NEAREST,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=L.VOID)


class CandidateEvaluator:
    """Evaluates ISP parameter sets against one scene's fisheye label image.

    Parameters
    ----------
    fisheye_labels : (H_i, W_i) uint8
        The rendered fisheye label image (read-only; shared by all candidates).
    output : OutputSpec
        RVM image size and mirroring during tuning.
    criteria : Criteria, optional
        Default: :func:`rvmsim.criteria.default_criteria`.
    windowed : bool
        Remap only the windows the ECs need (default); False remaps the whole image for every
        measurement (the slow reference the windowed path is tested against).
    """

    def __init__(self, fisheye_labels: np.ndarray, output: OutputSpec = OutputSpec(),
                 criteria: Criteria | None = None, *, windowed: bool = True):
        labels = np.ascontiguousarray(np.asarray(fisheye_labels))
        if labels.ndim != 2 or labels.dtype != np.uint8:
            raise TypeError("fisheye_labels must be a 2-D uint8 label image")
        self.fisheye = labels
        self.input_size = (labels.shape[1], labels.shape[0])
        self.output = output
        self.criteria = criteria or default_criteria()
        self.windowed = windowed
        names, boxes = _group_tiles(labels)
        self._tile_group = np.array([list(GROUPS).index(n) for n in names], dtype=np.intp)
        self._outline = _outlines(boxes)
        # Tiles come group by group: where each group's run of tiles starts.
        self._starts = np.flatnonzero(np.r_[True, np.diff(self._tile_group) != 0])
        # Coarse occupancy of the garnish/trunk pixels, for EC 2-4's quick "none up there".
        import cv2

        body = np.isin(labels, GROUPS["upper_body"]).astype(np.uint8)
        self._any_body = bool(body.any())
        gh, gw = -(-labels.shape[0] // _BLOCK_PX), -(-labels.shape[1] // _BLOCK_PX)
        padded = np.zeros((gh * _BLOCK_PX, gw * _BLOCK_PX), np.uint8)
        padded[: labels.shape[0], : labels.shape[1]] = body
        occ = padded.reshape(gh, _BLOCK_PX, gw, _BLOCK_PX).max(axis=(1, 3))
        self._body_blocks = cv2.dilate(occ, np.ones((3, 3), np.uint8))  # one block of slack

    def windows(self, params: IspParams) -> dict[str, Window]:
        """The RVM window each label group can appear in, for one parameter set."""
        w, h = self.output.width, self.output.height
        groups = list(GROUPS)
        out: dict[str, Window] = {n: (0, 0, 0, 0) for n in groups}
        if not len(self._tile_group):
            return out
        uv, ok = input_to_output(params, self._outline, self.input_size, self.output)
        per = 4 * _SIDE_SAMPLES
        uv = uv.reshape(-1, per, 2)
        tile_ok = ok.reshape(-1, per).all(axis=1) & np.isfinite(uv).all(axis=(1, 2))
        m = WINDOW_MARGIN_PX
        uv = np.where(np.isfinite(uv), uv, 0.0)
        lo = np.minimum.reduceat(np.floor(uv.min(axis=1)) - m, self._starts, axis=0)
        hi = np.maximum.reduceat(np.ceil(uv.max(axis=1)) + m + 1, self._starts, axis=0)
        all_ok = np.logical_and.reduceat(tile_ok, self._starts)
        lo = np.clip(lo, 0, [w, h]).astype(int)
        hi = np.clip(hi, 0, [w, h]).astype(int)
        for k, start in enumerate(self._starts):
            name = groups[self._tile_group[start]]
            if not all_ok[k]:
                out[name] = (0, 0, w, h)  # part of the group maps behind the image plane
            elif hi[k, 0] > lo[k, 0] and hi[k, 1] > lo[k, 1]:
                out[name] = (int(lo[k, 0]), int(lo[k, 1]), int(hi[k, 0]), int(hi[k, 1]))
        rows = int(round(self.criteria.upper_region_fraction * h))
        out["upper_body"] = (0, 0, 0, 0) if self._no_body_up_there(params) else (0, 0, w, rows)
        return out

    def _no_body_up_there(self, params: IspParams) -> bool:
        """True when no garnish/trunk pixel can appear in EC 2-4's upper region: the region's
        outline, mapped into the fisheye image, encloses no block that holds one."""
        import cv2

        w = self.output.width
        rows = int(round(self.criteria.upper_region_fraction * self.output.height))
        if rows <= 0 or not self._any_body:
            return True
        t = np.linspace(0.0, 1.0, 64, endpoint=False)
        u = np.concatenate([t * (w - 1), np.full_like(t, w - 1), (1 - t) * (w - 1), np.zeros_like(t)])
        v = np.concatenate([np.zeros_like(t), t * (rows - 1), np.full_like(t, rows - 1),
                            (1 - t) * (rows - 1)])
        ux, vy, _ = _map_points(params, u, v, self.input_size, self.output)
        poly = np.stack([ux, vy], 1) / _BLOCK_PX
        if not np.all(np.isfinite(poly)) or np.abs(poly).max() > 1e5:
            return False
        canvas = np.zeros_like(self._body_blocks)
        pts = np.round(poly * 16).astype(np.int32).reshape(-1, 1, 2)
        cv2.fillPoly(canvas, [pts], 1, cv2.LINE_8, shift=4)
        cv2.polylines(canvas, [pts], True, 1, 1, cv2.LINE_8, shift=4)
        return not np.any(canvas & self._body_blocks)

    def source(self, params: IspParams) -> LabelSource:
        """The label pixels of one candidate's RVM image, windowed or whole."""
        nodes = map_nodes(params, self.input_size, self.output)
        shape = (self.output.height, self.output.width)
        if self.windowed:
            windows = self.windows(params)
        else:
            windows = {n: (0, 0, self.output.width, self.output.height) for n in GROUPS}
        return _RemapSource(self.fisheye, nodes, windows, shape)

    def __call__(self, params: IspParams) -> EcResult:
        """The EC result of one parameter set."""
        c = self.criteria
        m = measure_source(self.source(params), upper_region_fraction=c.upper_region_fraction,
                           edge_columns=c.edge_columns)
        return score(m, c)
