"""One candidate on several fisheye label images of one size at once: the ISP map's nodes
built once, the label images remapped together, each image's ECs measured on its own
pixels (robust tuning's members: the nominal image and its variation samples).

The ISP map depends on the parameters, the fisheye image's size and the RVM output only,
not on what the image shows.  :class:`CandidateBatch` therefore, per candidate,

1. builds the map's node grid once (:func:`rvmsim.isp.map_nodes`) and what the windows read
   of it once (:meth:`CandidateEvaluator.node_lookup`);
2. finds each image's windows from its own group distances
   (:meth:`CandidateEvaluator.windows_at`), and merges every image's windows and fixed
   regions into one set of boxes;
3. remaps each box once for all images: the label images are packed as the channels of a
   few uint8 images (:data:`PACK`), each remapped in one ``cv2.remap`` call through the
   box's map, and split back into per-image planes;
4. measures each image's ECs (:func:`~rvmsim.criteria.measure.measure_ecs`) on its planes.

Exact: nearest-neighbour remapping reads each output pixel from the fisheye pixel its map
value rounds to, channel by channel, and a window's map is bit-identical to the same pixels
of the whole map (:meth:`rvmsim.isp.MapNodes.window`), so every pixel an EC reads equals the
one its own :class:`CandidateEvaluator` gives; the measurements are equal value for value
(tests/criteria/test_batched.py compares them on rendered variation samples).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import labels as L
from ..isp import IspParams, MapNodes, RayCache, map_nodes, remap_xy
from .context import IspView
from .evaluator import BoxedSource, CandidateEvaluator, merge_windows, remap_labels
from .groups import Window
from .measure import LabelSource, Measurements, measure_ecs
from .scoring import values_array

__all__ = ["CandidateBatch", "PACK"]

#: Label images per remap call: the channels of one uint8 image (OpenCV's remap runs its
#: vectorised path for up to 4 channels; tools/bench_robust_candidate.py).
PACK = 4


class _Planes:
    """The remapped boxes of one candidate, each made for every image on first use."""

    def __init__(self, packed: list[np.ndarray], n: int, nodes: MapNodes,
                 boxes: list[Window]):
        self.packed, self.n, self.nodes, self.boxes = packed, n, nodes, boxes
        self.made: dict[int, list[np.ndarray]] = {}

    def box(self, k: int) -> list[np.ndarray]:
        """Box ``k`` of every image: (h, w) uint8 planes, in image order."""
        planes = self.made.get(k)
        if planes is None:
            planes = self.made[k] = self._remap(self.boxes[k])
        return planes

    def _remap(self, win: Window) -> list[np.ndarray]:
        import cv2

        m = self.nodes.window(win)
        out: list[np.ndarray] = []
        for img in self.packed:
            r = remap_xy(img, m, cv2.INTER_NEAREST, (L.VOID,) * 4)
            out += [r] if r.ndim == 2 else list(cv2.split(r))
        return out[: self.n]


class _BatchSource(BoxedSource):
    """One image's label pixels of a candidate, cut from the batch's remapped boxes."""

    def __init__(self, planes: _Planes, member: int, groups: dict[str, Window],
                 shape: tuple[int, int], evaluator: CandidateEvaluator, isp: IspView):
        self.planes = planes
        self.member = member
        self.groups = groups
        self.boxes = planes.boxes
        self.shape = shape
        self.evaluator = evaluator
        self.context = evaluator.context
        self.isp = isp
        self._shared = {}

    def box_image(self, k: int) -> np.ndarray:
        return self.planes.box(k)[self.member]

    def remap(self, win: Window) -> np.ndarray:
        return remap_labels(self.evaluator.fisheye, self.planes.nodes, win)


class CandidateBatch:
    """Candidates judged on several fisheye label images of one size, each with its own
    :class:`CandidateEvaluator` (its criteria, scene and windows), sharing each candidate's
    map (see the module docstring).

    Parameters
    ----------
    evaluators : sequence of CandidateEvaluator
        One per image: every one of the same fisheye size and RVM output, windowed.

    Raises
    ------
    ValueError
        Evaluators of different fisheye sizes or outputs, or not windowed.

    Picklable: the packed label images are made again on first use after unpickling.
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
        self._rays = RayCache()
        self._packed: list[np.ndarray] | None = None

    def __getstate__(self) -> dict[str, object]:
        return {**self.__dict__, "_packed": None}

    def packed(self) -> list[np.ndarray]:
        """The label images as the channels of uint8 images of :data:`PACK` channels (the
        last one with fewer; one channel: a 2-D image)."""
        if self._packed is None:
            self._packed = _pack([ev.fisheye for ev in self.evaluators])
        return self._packed

    def sources(self, params: IspParams, members: Sequence[int] | None = None
                ) -> list[LabelSource]:
        """The label sources of one candidate on the images ``members`` (default: all)."""
        idx = list(range(len(self.evaluators))) if members is None else list(members)
        evs = [self.evaluators[m] for m in idx]
        nodes = map_nodes(params, self.input_size, self.output, rays=self._rays)
        lookup = evs[0].node_lookup(nodes) if evs else None
        groups = [ev.windows_at(lookup) for ev in evs]
        wins = [w for g, ev in zip(groups, evs) for w in [*g.values(), *ev.regions]]
        packed = self.packed() if members is None else _pack([ev.fisheye for ev in evs])
        planes = _Planes(packed, len(evs), nodes, merge_windows(list(dict.fromkeys(wins))))
        isp = IspView(params, self.input_size, self.output)
        shape = (self.output.height, self.output.width)
        return [_BatchSource(planes, k, g, shape, ev, isp)
                for k, (g, ev) in enumerate(zip(groups, evs))]

    def measure(self, params: IspParams, members: Sequence[int] | None = None
                ) -> list[Measurements]:
        """The raw measurements of one parameter set on every image (or ``members``)."""
        idx = list(range(len(self.evaluators))) if members is None else list(members)
        out = []
        for m, src in zip(idx, self.sources(params, idx if members is not None else None)):
            c = self.evaluators[m].criteria
            out.append(measure_ecs(src, c.ecs, c.options))
        return out

    def values(self, params: IspParams, members: Sequence[int] | None = None
               ) -> list[np.ndarray]:
        """Each image's measured values (:meth:`CandidateEvaluator.values`)."""
        idx = list(range(len(self.evaluators))) if members is None else list(members)
        return [values_array(m, self.evaluators[k].criteria.ids)
                for k, m in zip(idx, self.measure(params, members))]


def _pack(labels: list[np.ndarray]) -> list[np.ndarray]:
    """Label images as the channels of :data:`PACK`-channel uint8 images (a lone last one
    stays 2-D)."""
    return [np.ascontiguousarray(np.dstack(labels[a : a + PACK]))
            if len(labels[a : a + PACK]) > 1 else labels[a]
            for a in range(0, len(labels), PACK)]
