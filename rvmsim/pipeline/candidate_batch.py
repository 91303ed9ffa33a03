"""One candidate on several fisheye label images of one size at once: the ISP map's nodes
built once, the label images remapped together, each image's ECs measured on its own
pixels (robust tuning's members: the nominal image and its variation samples).

The ISP map depends on the parameters, the fisheye image's size and the RVM output only,
not on what the image shows.  :class:`CandidateBatch` therefore, per candidate,

1. builds the map's node grid once (:func:`rvmsim.isp.map_nodes`) and what the windows read
   of it once (:meth:`CandidateEvaluator.node_lookup`);
2. finds the windows once for every image (:func:`union_windows`: from the group
   distances of all images at once; each image's own, when their criteria differ), and
   merges them and the fixed regions into one set of boxes;
3. remaps each box once for all images: the label images are the channels of one uint8
   image (K channels), remapped in one ``cv2.remap`` call through the box's map, and each
   image's plane is cut from it when first read;
4. measures the ECs: with one set of ECs and windows for every image, each EC with a stack
   measure on all images in one call (:func:`~rvmsim.criteria.stack.measure_stack_ecs`
   on a :class:`~rvmsim.criteria.LabelStack` of the remapped boxes), any other one on
   each image's planes (:func:`~rvmsim.criteria.measure.measure_ecs`).

Exact: nearest-neighbour remapping reads each output pixel from the fisheye pixel its map
value rounds to, channel by channel, and a window's map is bit-identical to the same pixels
of the whole map (:meth:`rvmsim.isp.MapNodes.window`), so every pixel an EC reads equals the
one its own :class:`CandidateEvaluator` gives; a union window holds each image's group
pixels and their neighbours, as its own window does, so the measurements are equal value
for value (tests/tune/test_batched_members.py compares them on rendered variation
samples).
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from .. import labels as L
from ..criteria.context import IspView
from ..criteria.groups import Window
from ..criteria.measure import LabelSource, Measurements, measure_ecs
from ..criteria.scoring import values_array
from ..criteria.stack import LabelStack, measure_stack_ecs
from ..isp import IspParams, MapNodes, RayCache, map_nodes, remap_xy
from .candidate import (BoxedSource, CandidateEvaluator, box_holding, merge_windows, remap_labels,
                        union_windows)

__all__ = ["CandidateBatch"]

# Outside the fisheye image a remap reads the border value, whose channels past the fourth
# OpenCV fills with 0: the label images' channels read VOID there only because VOID is 0.
assert L.VOID == 0, "CandidateBatch's K-channel remap fills the outside with 0"


class _Planes:
    """The remapped boxes of one candidate: each box remapped once for every image (a
    (h, w, K) uint8 stack) on first use, each image's plane of it cut when first read."""

    def __init__(self, stack: np.ndarray, nodes: MapNodes, boxes: list[Window]):
        self.stack, self.nodes, self.boxes = stack, nodes, boxes
        self.made: dict[int, np.ndarray] = {}
        self.cut: dict[tuple[int, int], np.ndarray] = {}

    def box(self, k: int) -> np.ndarray:
        """Box ``k`` of every image: (h, w, K) uint8, channel c the image of channel c."""
        got = self.made.get(k)
        if got is None:
            got = remap_xy(self.stack, self.nodes.window(self.boxes[k]), cv2.INTER_NEAREST,
                           (L.VOID,) * 4)
            got = self.made[k] = got.reshape(*got.shape[:2], self.stack.shape[2])
        return got

    def plane(self, k: int, channel: int) -> np.ndarray:
        """Box ``k`` of the image of ``channel``: (h, w) uint8, C-contiguous."""
        got = self.cut.get((k, channel))
        if got is None:
            got = self.cut[(k, channel)] = np.ascontiguousarray(self.box(k)[:, :, channel])
        return got


class _BatchSource(BoxedSource):
    """One image's label pixels of a candidate, cut from the batch's remapped boxes."""

    def __init__(self, planes: _Planes, channel: int, groups: dict[str, Window],
                 shape: tuple[int, int], evaluator: CandidateEvaluator, isp: IspView):
        self.planes = planes
        self.channel = channel
        self.groups = groups
        self.boxes = planes.boxes
        self.shape = shape
        self.evaluator = evaluator
        self.context = evaluator.context
        self.isp = isp
        self._shared = {}

    def box_image(self, k: int) -> np.ndarray:
        return self.planes.plane(k, self.channel)

    def remap(self, win: Window) -> np.ndarray:
        return remap_labels(self.evaluator.fisheye, self.planes.nodes, win)


class _BatchStack(LabelStack):
    """The label pixels of one candidate on the images of ``channels``, cut from the
    batch's remapped boxes (each image's own source in :attr:`sources`)."""

    def __init__(self, planes: _Planes, channels: list[int], groups: dict[str, Window],
                 shape: tuple[int, int], sources: list[LabelSource]):
        self.planes = planes
        self.channels = channels
        self.every = channels == list(range(planes.stack.shape[2]))
        self._windows = groups
        self.shape = shape
        self.n = len(channels)
        self.sources = sources
        self._shared = {}

    def pixels(self, win: Window) -> np.ndarray:
        x0, y0, x1, y1 = win
        if x1 <= x0 or y1 <= y0:
            return np.zeros((0, 0, self.n), np.uint8)
        k = box_holding(self.planes.boxes, win)
        if k is None:
            got = remap_xy(self.planes.stack, self.planes.nodes.window(win),
                           cv2.INTER_NEAREST, (L.VOID,) * 4)
            got = got.reshape(*got.shape[:2], self.planes.stack.shape[2])
        else:
            bx0, by0 = self.planes.boxes[k][:2]
            got = self.planes.box(k)[y0 - by0 : y1 - by0, x0 - bx0 : x1 - bx0]
        return got if self.every else got[:, :, self.channels]


class CandidateBatch:
    """Candidates judged on several fisheye label images of one size, each with its own
    :class:`CandidateEvaluator` (its criteria, scene and windows), sharing each candidate's
    map, windows and remaps (see the module docstring).

    Parameters
    ----------
    evaluators : sequence of CandidateEvaluator
        One per image: every one of the same fisheye size and RVM output, windowed.

    Raises
    ------
    ValueError
        Evaluators of different fisheye sizes or outputs, or not windowed.

    Picklable: the stacked label images are made again on first use after unpickling.
    """

    def __init__(self, evaluators: Sequence[CandidateEvaluator]):
        self.evaluators = list(evaluators)
        if not self.evaluators:
            raise ValueError("a candidate batch needs at least one evaluator")
        first = self.evaluators[0]
        for ev in self.evaluators:
            if (ev.input_size != first.input_size or ev.output != first.output
                    or not ev.windowed):
                raise ValueError("a candidate batch takes windowed evaluators of one fisheye "
                                 "size and RVM output")
        self.input_size, self.output = first.input_size, first.output
        #: One evaluator whose windows hold every image's (None: each finds its own).
        self._union = union_windows(self.evaluators)
        self._regions = list(dict.fromkeys(r for ev in self.evaluators for r in ev.regions))
        #: One set of windows, ECs and options for every image: measured as one stack.
        c0 = first.criteria
        self._same_ecs = self._union is not None and all(
            ev.criteria.ecs == c0.ecs and ev.criteria.options == c0.options
            for ev in self.evaluators)
        self._rays = RayCache()
        self._stack: np.ndarray | None = None

    def __getstate__(self) -> dict[str, object]:
        return {**self.__dict__, "_stack": None}

    def stack(self) -> np.ndarray:
        """The label images as the channels of one (H_i, W_i, K) uint8 image."""
        if self._stack is None:
            self._stack = np.ascontiguousarray(
                np.stack([ev.fisheye for ev in self.evaluators], axis=2))
        return self._stack

    def _windows(self, nodes: MapNodes, idx: list[int]) -> list[dict[str, Window]]:
        """Each image's group windows of a candidate (the union's, when there is one)."""
        evs = [self.evaluators[m] for m in idx]
        if self._union is not None:
            return [self._union.windows_at(self._union.node_lookup(nodes))] * len(idx)
        lookup = evs[0].node_lookup(nodes)
        return [ev.windows_at(lookup) for ev in evs]

    def sources(self, params: IspParams, members: Sequence[int] | None = None
                ) -> list[LabelSource]:
        """The label sources of one candidate on the images ``members`` (default: all)."""
        idx = list(range(len(self.evaluators))) if members is None else list(members)
        nodes = map_nodes(params, self.input_size, self.output, rays=self._rays)
        groups = self._windows(nodes, idx)
        wins = [w for g in groups for w in g.values()] + self._regions
        planes = _Planes(self.stack(), nodes, merge_windows(list(dict.fromkeys(wins))))
        isp = IspView(params, self.input_size, self.output)
        shape = (self.output.height, self.output.width)
        return [_BatchSource(planes, m, g, shape, self.evaluators[m], isp)
                for m, g in zip(idx, groups)]

    def measure(self, params: IspParams, members: Sequence[int] | None = None
                ) -> list[Measurements]:
        """The raw measurements of one parameter set on every image (or ``members``): with
        one set of ECs and windows for all, each EC with a stack measure measures every
        image in one call (:func:`rvmsim.criteria.measure_stack_ecs`)."""
        idx = list(range(len(self.evaluators))) if members is None else list(members)
        sources = self.sources(params, idx)
        if self._same_ecs and sources:
            c = self.evaluators[idx[0]].criteria
            first = sources[0]
            assert isinstance(first, _BatchSource)
            stack = _BatchStack(first.planes, idx, first.groups, first.shape, sources)
            return measure_stack_ecs(stack, c.ecs, c.options)
        out = []
        for m, src in zip(idx, sources):
            c = self.evaluators[m].criteria
            out.append(measure_ecs(src, c.ecs, c.options))
        return out

    def values(self, params: IspParams, members: Sequence[int] | None = None
               ) -> list[np.ndarray]:
        """Each image's measured values (:meth:`CandidateEvaluator.values`)."""
        idx = list(range(len(self.evaluators))) if members is None else list(members)
        return [values_array(m, self.evaluators[k].criteria.ids)
                for k, m in zip(idx, self.measure(params, members))]
