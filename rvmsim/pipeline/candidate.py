"""Fast per-candidate evaluation for tuning: ISP map → label windows → ECs → EC score.

:func:`rvmsim.criteria.evaluate` needs the whole RVM label image.  Tuning only needs the
measurements, and each looks at groups of labels (F's stripe, the board, …) that
covers a small part of the image.  :class:`CandidateEvaluator` therefore

1. computes, once per scene, the distance image of each label group the selected ECs declare
   (:attr:`EcDefinition.groups`) over the fisheye image: the
   Chebyshev distance (px) from every pixel to the group's nearest pixel, kept as the
   minimum per 4×4 block;
2. per candidate, reads those distances under every node of the ISP map's node grid
   (:func:`isp.map_nodes`, which the remap needs anyway) and flags a node for a group when
   the group is within reach of it; the group's window is the box of its flagged nodes;
3. remaps only those windows (plus the fixed regions ECs declare, such as the bumper's
   columns; merged where one remap of a union is cheaper than two) and measures them with
   exactly the code that measures whole images (each EC's measure function).  Groups read
   only in the upper region (:attr:`LabelGroup.upper_region`) are remapped there only.

Why step 2 is exact: the fast map *is* the bilinear interpolation of the nodes, so an output
pixel of a cell reads the fisheye label nearest to a point inside the box of the cell's four
corner nodes, i.e. within (box extent + 1 px) of each corner, per axis.  A node is flagged
when a group pixel is within (largest extent of the four cells around it + margin), so all
four corners of any cell that shows a group pixel are flagged, and the cell lies inside the
box of the flagged nodes.  Node positions are clipped to the fisheye image padded by
``_PAD_PX`` first (clipping is monotone: the clipped box still holds the clipped point, and the
label pixel, being inside the image, is no farther from it).  When the map was refined to a
finer grid, the windows come from the first, coarser grid with its estimated error (twice
over) added to the margin.

The result equals ``evaluate(apply_map(labels, build_map(params, …)))`` pixel for pixel; the
tests check this on random candidates.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..criteria.config import default_criteria
from ..criteria.context import IspView, SceneContext, scene_context
from ..criteria.groups import EMPTY_WINDOW, LabelGroup, Window, group_chunks, group_window
from ..criteria.measure import LabelSource, Measurements, call_ec, measure_ecs
from ..criteria.scoring import Criteria, EcResult, score, values_array
from ..isp import InputWarp, IspParams, MapNodes, OutputSpec, RayCache, map_nodes, remap_xy
from ..scene import Scene

__all__ = ["CandidateEvaluator", "NodeLookup", "BoxedSource", "box_holding", "group_window",
           "merge_windows", "remap_labels", "union_windows"]

#: Fisheye px around the image that node positions are clipped to.
_PAD_PX = 8
#: Fisheye px per block of the stored group distances.
_DIST_BLOCK_PX = 4
#: Distances are stored in 7 bits (eight groups packed in one uint64 per pixel, compared all
#: at once); farther than this counts as "far", and reaches beyond it flag every node.
_FAR_PX = 127
_BYTES = np.uint64(0x0101010101010101)
_HIGH_BITS = np.uint64(0x8080808080808080)
#: A coarse grid whose estimated error exceeds this is not used for windows.
_COARSE_ERROR_LIMIT_PX = 4.0


def _group_distances(labels: np.ndarray, groups: tuple[LabelGroup, ...]) -> np.ndarray:
    """Per ``_DIST_BLOCK_PX``-square block of the fisheye image padded by ``_PAD_PX``: a uint64
    whose byte k is the smallest Chebyshev distance (px, capped at ``_FAR_PX``) from a pixel
    of the block to the nearest pixel of ``groups[k]`` (at most eight groups).  (rows, cols)
    uint64; small enough (~0.6 MB) to stay in the cache."""

    if len(groups) > 8:
        raise ValueError("at most 8 label groups per distance image")
    h, w = labels.shape
    b = _DIST_BLOCK_PX
    gh, gw = -(-(h + 2 * _PAD_PX) // b), -(-(w + 2 * _PAD_PX) // b)
    out = np.full((gh, gw, 8), _FAR_PX, np.uint8)
    block = np.ones((b, b), np.uint8)
    for k, group in enumerate(groups):
        far = np.full((gh * b, gw * b), 255, np.uint8)
        far[_PAD_PX : _PAD_PX + h, _PAD_PX : _PAD_PX + w] = 255 - cv2.LUT(labels, group.lut)
        x, y, bw, bh = cv2.boundingRect((far == 0).view(np.uint8))
        if bw == 0:
            continue
        # only the blocks within _FAR_PX + 1 of the group's box can be nearer than "far";
        # the chessboard distance of a pixel there to the group's nearest pixel is the
        # same inside that rectangle (it holds the group) as over the whole image
        x0, y0 = max(0, (x - _FAR_PX - 1) // b * b), max(0, (y - _FAR_PX - 1) // b * b)
        x1 = min(gw * b, -(-(x + bw + _FAR_PX + 1) // b) * b)
        y1 = min(gh * b, -(-(y + bh + _FAR_PX + 1) // b) * b)
        dist = np.minimum(cv2.distanceTransform(far[y0:y1, x0:x1], cv2.DIST_C, 3), _FAR_PX)
        # each block's minimum: a b×b minimum filter anchored at its top-left pixel, read
        # at the blocks' corners (12× faster than a reduction over two axes)
        low = cv2.erode(dist, block, anchor=(0, 0), borderType=cv2.BORDER_REPLICATE)
        out[y0 // b:y1 // b, x0 // b:x1 // b, k] = low[::b, ::b].astype(np.uint8)
    return np.ascontiguousarray(out).view("<u8")[..., 0]


_K2 = np.ones((2, 2), np.uint8)


def _node_reach(grid: np.ndarray) -> np.ndarray:
    """Per node, the largest extent (px, along x or y) of the up to four cells around it:
    (rows, cols) float32.  ``grid`` is (rows, cols, 2) float32 node positions."""

    # cell (i, j) has corners (i..i+1, j..j+1): max/min over a 2×2 window anchored top-left
    hi = cv2.dilate(grid, _K2, anchor=(0, 0), borderType=cv2.BORDER_REPLICATE)
    lo = cv2.erode(grid, _K2, anchor=(0, 0), borderType=cv2.BORDER_REPLICATE)
    ext = cv2.subtract(hi, lo)
    ext = cv2.max(ext[..., 0], ext[..., 1])
    # node (i, j) touches cells (i−1..i, j−1..j)
    return cv2.dilate(ext, _K2, anchor=(1, 1), borderType=cv2.BORDER_REPLICATE)


#: Cost model for remapping windows (µs per call, µs per output px; this machine): windows
#: are merged where one remap of their union is cheaper than two, e.g. for views where the
#: objects fill most of the image.
_CALL_US, _PX_US = 20.0, 0.0025


def box_holding(boxes: Sequence[Window], win: Window) -> int | None:
    """The index of the first of ``boxes`` that holds window ``win`` whole, or None."""
    x0, y0, x1, y1 = win
    for k, (bx0, by0, bx1, by1) in enumerate(boxes):
        if bx0 <= x0 and by0 <= y0 and x1 <= bx1 and y1 <= by1:
            return k
    return None


def merge_windows(windows: list[Window]) -> list[Window]:
    """Boxes to remap so that every window lies in one of them, merging windows where one
    remap of their union costs less than two (``_CALL_US``, ``_PX_US``); greedy, in order."""
    boxes: list[list[int]] = []
    for x0, y0, x1, y1 in windows:
        if x1 <= x0 or y1 <= y0:
            continue
        area = (x1 - x0) * (y1 - y0)
        for b in boxes:
            u = [min(b[0], x0), min(b[1], y0), max(b[2], x1), max(b[3], y1)]
            if _PX_US * ((u[2] - u[0]) * (u[3] - u[1]) - (b[2] - b[0]) * (b[3] - b[1]) - area) < _CALL_US:
                b[:] = u
                break
        else:
            boxes.append([x0, y0, x1, y1])
    return [tuple(b) for b in boxes]  # type: ignore[misc]


def remap_labels(fisheye: np.ndarray, nodes: MapNodes, win: Window) -> np.ndarray:
    """The label pixels of output window ``win`` through the map ``nodes`` (nearest
    neighbour; outside the fisheye image :data:`rvmsim.labels.VOID`)."""

    return remap_xy(fisheye, nodes.window(win), cv2.INTER_NEAREST, L.VOID)


class BoxedSource(LabelSource):
    """Label pixels of one candidate cut from a few remapped boxes that hold its windows
    (``boxes``); a window no box holds is remapped alone (:meth:`remap`).  Subclasses give
    ``groups``, ``boxes``, :meth:`box_image` and :meth:`remap`."""

    groups: dict[str, Window]
    boxes: Sequence[Window]

    def box_image(self, k: int) -> np.ndarray:
        """The label pixels of box ``k``."""
        raise NotImplementedError

    def remap(self, win: Window) -> np.ndarray:
        """The label pixels of window ``win`` alone."""
        raise NotImplementedError

    def window(self, group: LabelGroup | str) -> Window:
        return group_window(self.groups, group)

    def pixels(self, win: Window) -> np.ndarray:
        x0, y0, x1, y1 = win
        if x1 <= x0 or y1 <= y0:
            return np.zeros((0, 0), np.uint8)
        k = box_holding(self.boxes, win)
        if k is None:
            return self.remap(win)
        bx0, by0 = self.boxes[k][:2]
        return self.box_image(k)[y0 - by0 : y1 - by0, x0 - bx0 : x1 - bx0]


class _RemapSource(BoxedSource):
    """Label pixels of one candidate: the windows are merged into a few boxes
    (:func:`merge_windows`), remapped on first use."""

    def __init__(self, fisheye: np.ndarray, nodes: MapNodes, windows: list[Window],
                 shape: tuple[int, int], groups: dict[str, Window], *,
                 context: SceneContext | None, isp: IspView):
        self.context = context
        self.isp = isp
        self.fisheye = fisheye
        self.nodes = nodes
        self.groups = groups
        self.shape = shape
        self.boxes = merge_windows(windows)
        self.images: dict[int, np.ndarray] = {}
        self._shared = {}

    def remap(self, win: Window) -> np.ndarray:
        return remap_labels(self.fisheye, self.nodes, win)

    def box_image(self, k: int) -> np.ndarray:
        img = self.images.get(k)
        if img is None:
            img = self.images[k] = self.remap(self.boxes[k])
        return img


@dataclass(frozen=True)
class NodeLookup:
    """A candidate's node grid as :meth:`CandidateEvaluator.windows_at` reads it: each
    node's block in the stored group distances (``flat``, (rows, cols) intp), its reach
    (px, in every byte of ``reach_bytes``, with the high bits set) and the grid's spacing
    ``cell`` (output px)."""

    flat: np.ndarray
    reach_bytes: np.ndarray
    cell: float


class CandidateEvaluator:
    """Evaluates ISP parameter sets against one scene's fisheye label image.

    Parameters
    ----------
    fisheye_labels : (H_i, W_i) uint8
        The rendered fisheye label image (read-only; shared by all candidates).
    output : OutputSpec
        RVM image size and mirroring during tuning.
    criteria : Criteria, optional
        Default: :func:`rvmsim.criteria.default_criteria`.  Any registered ECs: the windows
        come from the label groups and regions they declare.
    windowed : bool
        Remap only the windows the ECs need (default); False remaps the whole image for every
        measurement (the slow reference the windowed path is tested against).
    scene : Scene, optional
        The scene the labels were rendered from: ECs that need its geometry or display
        read it (``source.context``, :class:`rvmsim.criteria.SceneContext`); without it they
        cannot be measured.
    camera : FisheyeCamera, optional
        The camera the labels were rendered with (default: the scene's, scaled to the
        labels' size).

    Notes
    -----
    Pickles (to tuning's worker processes) with its criteria, whose ECs pickle by reference
    to their plugin.
    """

    def __init__(self, fisheye_labels: np.ndarray, output: OutputSpec = OutputSpec(),
                 criteria: Criteria | None = None, *, windowed: bool = True,
                 scene: Scene | None = None, camera: FisheyeCamera | None = None):
        labels = np.ascontiguousarray(np.asarray(fisheye_labels))
        if labels.ndim != 2 or labels.dtype != np.uint8:
            raise TypeError("fisheye_labels must be a 2-D uint8 label image")
        self.fisheye = labels
        self.input_size = (labels.shape[1], labels.shape[0])
        self.output = output
        self.criteria = criteria or default_criteria()
        self.windowed = windowed
        #: The scene as the ECs see it (None without a scene).
        self.context = scene_context(scene, camera, labels)
        self._rays = RayCache()  # views recur in the coarse grid with other FOV/RAD/shifts
        # one distance image per eight groups
        self._chunks = group_chunks(self.criteria.groups)
        dists = [_group_distances(labels, chunk) for chunk in self._chunks]
        self._dists = [d.ravel() for d in dists]
        self._dist_width = dists[0].shape[1] if dists else 0
        # fixed regions the ECs read (e.g. the bumper's columns), each once
        shape, options = (output.height, output.width), self.criteria.options
        self._regions: list[Window] = list(dict.fromkeys(
            (int(x0), int(y0), int(x1), int(y1)) for ec in self.criteria.ecs if ec.regions
            for x0, y0, x1, y1 in call_ec(ec, "regions", f"a {output.width}x{output.height} "
                                          "RVM image", ec.regions, shape, options)))

    @property
    def regions(self) -> list[Window]:
        """The fixed RVM regions the ECs read (e.g. the bumper's columns), each once."""
        return self._regions

    def _whole(self) -> dict[str, Window]:
        w, h = self.output.width, self.output.height
        rows = self.criteria.options.upper_rows(h)
        return {g.name: (0, 0, w, rows if g.upper_region else h) for g in self.criteria.groups}

    def windows(self, params: IspParams, nodes: MapNodes | None = None) -> dict[str, Window]:
        """The RVM window each label group can appear in, for one parameter set (``nodes``:
        its map's node grid, when already built)."""
        if nodes is None:
            nodes = self.map_nodes(params)
        return self.windows_at(self.node_lookup(nodes))

    def node_lookup(self, nodes: MapNodes) -> NodeLookup | None:
        """What :meth:`windows_at` reads of a candidate's node grid: the same for every
        evaluator of this input size and output (None: the windows are the whole image)."""

        # nearest rounding (1 px) + distances are block minima: a node's own distance is at
        # least its block's minimum − the block size
        use, margin = nodes, 1.0 + _DIST_BLOCK_PX
        first = nodes.first
        if first is not None and first.grid is not None and first.error_px <= _COARSE_ERROR_LIMIT_PX:
            use, margin = first, margin + 2.0 * (first.error_px + nodes.error_px)
        if use.grid is None:
            return None
        iw, ih = self.input_size
        lo, hi = (-_PAD_PX, -_PAD_PX, 0, 0), (iw - 1 + _PAD_PX, ih - 1 + _PAD_PX, 0, 0)
        grid = cv2.min(cv2.max(use.grid, lo), hi)  # type: ignore[call-overload, unused-ignore]
        reach = np.minimum(_node_reach(grid) + margin, _FAR_PX).astype(np.uint64)
        # block of each node (floor: positions are ≥ 0 here)
        idx = ((grid + _PAD_PX) * (1.0 / _DIST_BLOCK_PX)).astype(np.intp)
        flat = idx[..., 1] * self._dist_width + idx[..., 0]
        return NodeLookup(flat, reach * _BYTES | _HIGH_BITS, use.cell)

    def windows_at(self, lookup: NodeLookup | None) -> dict[str, Window]:
        """:meth:`windows` from a candidate's :meth:`node_lookup`."""
        if lookup is None or not self._chunks:
            return self._whole()
        out: dict[str, Window] = {}
        for chunk, dists in zip(self._chunks, self._dists):
            # bytewise "distance ≤ reach" for all groups at once: each byte of
            # (reach | 0x80) − distance is 128 + reach − distance ≥ 1 (both ≤ 127, no borrow)
            flags = (lookup.reach_bytes - np.take(dists, lookup.flat)) & _HIGH_BITS
            flags = np.ascontiguousarray(flags[..., None].view(np.uint8).transpose(2, 0, 1))
            for k, group in enumerate(chunk):
                out[group.name] = self._window(flags[k], lookup.cell, group)
        return out

    def _window(self, flags: np.ndarray, c: float, group: LabelGroup) -> Window:
        """The output window of the cells between a group's flagged nodes."""

        w, h = self.output.width, self.output.height
        jx, jy, nw, nh = cv2.boundingRect(flags)
        if nw == 0:
            return EMPTY_WINDOW
        # node j sits at output (j − 1.5)·c − 0.5; cells between flagged nodes only
        # (grown by 1 px: the ring around a patch that a visibility check inspects)
        y_end = self.criteria.options.upper_rows(h) if group.upper_region else h
        x0 = max(0, math.floor((jx - 1.5) * c - 0.5) - 1)
        y0 = max(0, math.floor((jy - 1.5) * c - 0.5) - 1)
        x1 = min(w, math.ceil((jx + nw - 2.5) * c - 0.5) + 2)
        y1 = min(y_end, math.ceil((jy + nh - 2.5) * c - 0.5) + 2)
        return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else EMPTY_WINDOW

    def map_nodes(self, params: IspParams) -> MapNodes:
        """The node grid of one parameter set's map (:func:`rvmsim.isp.map_nodes`, with
        this evaluator's ray cache): what :meth:`source` reads through, for a caller that
        evaluates one parameter set with several evaluators of the same image size and
        output (:class:`rvmsim.percar.SplitEvaluator`)."""
        return map_nodes(params, self.input_size, self.output, rays=self._rays)

    def source(self, params: IspParams, warp: InputWarp | None = None,
               nodes: MapNodes | None = None) -> LabelSource:
        """The label pixels of one candidate's RVM image, windowed or whole; with ``warp``,
        of the fisheye image read where ``warp`` sends each of the map's positions
        (:meth:`rvmsim.isp.MapNodes.warped`: e.g. the image of a turned camera);
        ``nodes``: the map's node grid when already built (:meth:`map_nodes`)."""
        if nodes is None:
            nodes = self.map_nodes(params)
        if warp is not None:
            nodes = nodes.warped(warp)
        w, h = self.output.width, self.output.height
        groups = self.windows(params, nodes) if self.windowed else self._whole()
        return _RemapSource(self.fisheye, nodes, list(groups.values()) + self._regions, (h, w),
                            groups, context=self.context,
                            isp=IspView(params, self.input_size, self.output))

    def measure(self, params: IspParams, warp: InputWarp | None = None,
                nodes: MapNodes | None = None) -> Measurements:
        """The raw measurements of one parameter set (``warp``, ``nodes``: as
        :meth:`source`)."""
        c = self.criteria
        return measure_ecs(self.source(params, warp, nodes), c.ecs, c.options)

    def values(self, params: IspParams, warp: InputWarp | None = None,
               nodes: MapNodes | None = None) -> np.ndarray:
        """The measured values of one parameter set, (k,) in ``criteria.ids`` order, NaN
        where not measured (what tuning ships between processes; see ``score_batch``;
        ``warp``, ``nodes``: as :meth:`source`)."""
        return values_array(self.measure(params, warp, nodes), self.criteria.ids)

    def __call__(self, params: IspParams) -> EcResult:
        """The EC result of one parameter set."""
        return score(self.measure(params), self.criteria)


def union_windows(evaluators: Sequence[CandidateEvaluator]) -> CandidateEvaluator | None:
    """An evaluator whose windows hold every evaluator's: the first one with each group's
    stored distances replaced by their minimum over ``evaluators`` (the distance to the
    group's nearest pixel in any of their label images).  Its windows (:meth:`windows_at`)
    are those of the union of their groups' pixels, so each one holds the group's pixels,
    and the pixels next to them, on every image, and every EC measures on them what it
    measures on the image's own windows (any window that holds a group's pixels gives the
    same value).  None when the evaluators' criteria declare other groups or upper regions,
    or their fisheye sizes or outputs differ (each then finds its own windows).

    Exact for the same reason as :meth:`windows_at` (module docstring): a group pixel of
    any image is within the stored distance of every node of a cell that shows it."""

    if not evaluators:
        return None
    first = evaluators[0]
    key = (first.input_size, first.output, first.criteria.groups,
           first.criteria.options.upper_region_fraction)
    if any((ev.input_size, ev.output, ev.criteria.groups,
            ev.criteria.options.upper_region_fraction) != key for ev in evaluators):
        return None
    out = copy.copy(first)
    out._dists = [  # bytewise: each byte is one group's distance
        np.minimum.reduce([ev._dists[k].view(np.uint8) for ev in evaluators]).view("<u8")
        for k in range(len(first._dists))]
    return out
