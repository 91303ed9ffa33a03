"""The evaluators :func:`rvmsim.pipeline.make_evaluator` chooses among (its module,
:mod:`rvmsim.pipeline.factory`, says which it picks for what).

Every evaluator judges at the RVM image of record (:mod:`rvmsim.criteria.record`: the
display output, default 1280 × 720).  Asked to measure at another size, it judges by
:class:`rvmsim.pipeline.record_rule.RecordRule`: a pass is a pass on the display, whatever
size the search measures at.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterator, Sequence
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from .._progress import progress_bar
from ..camera import FisheyeCamera
from ..criteria import (Criteria, EcBatch, EcResult, Measurements, measure_labels,
                        scene_context, score, score_batch, values_array)
from ..isp import IspParams, OutputSpec, process
from ..scene import Scene
from .frame import evaluate_rvm_labels
from .pixels import RayTable, RvmPixels, ray_table, rvm_pixels
from .record_rule import RecordRule

if TYPE_CHECKING:
    from .._progress import ProgressBar

__all__ = ["EvaluationPath", "FisheyeLabels", "FisheyeSet", "ImageEvaluator", "FullEvaluator",
           "RecordEvaluator", "SetEvaluator"]

#: Images of a batch held at once (bounds the memory of label images in flight).
_CHUNK = 32
#: The same with one setting per image on the RVM-pixel path (RVM label images only).
_CHUNK_EACH = 256


class EvaluationPath(str, enum.Enum):
    """How an evaluator gets the RVM labels it measures (see the module docstring)."""

    WINDOWED = "windowed"
    FULL = "full"
    RVM_PIXELS = "rvm-pixels"


class FisheyeLabels(Protocol):
    """One fisheye label image with the camera that saw it and the scene it shows (None when
    unknown): :class:`rvmsim.render.FisheyeImages`, a tuning member, …"""

    @property
    def labels(self) -> np.ndarray: ...

    @property
    def camera(self) -> FisheyeCamera: ...

    @property
    def scene(self) -> Scene | None: ...


@runtime_checkable
class FisheyeSet(Protocol):
    """A batch of fisheye images that one ISP setting is judged on: one lens and sensor size
    (``camera``, at the images' size), one scene (None when unknown), each image its own pose.

    ``fisheye(indices)`` yields those images' whole label images (with their own cameras);
    ``rvm_labels(pixels, indices)`` yields their RVM label images under the setting of
    ``pixels``, reading only the fisheye pixels it lists — equal to
    ``process(None, image.labels, params, output)[1]`` (implementations test this).
    ``pixels`` may instead be a function of the position ``k`` in ``indices`` giving that
    image's own :class:`RvmPixels` (one setting per image: per-car values), called as each
    image is reached (so that images sharing a render are made together).
    """

    @property
    def camera(self) -> FisheyeCamera: ...

    @property
    def scene(self) -> Scene | None: ...

    def __len__(self) -> int: ...

    def fisheye(self, indices: Sequence[int]) -> Iterator[FisheyeLabels]: ...

    def rvm_labels(self, pixels: RvmPixels | Callable[[int], RvmPixels],
                   indices: Sequence[int]) -> Iterator[np.ndarray]: ...


class ImageEvaluator(Protocol):
    """A candidate's ECs on one fisheye label image (``fisheye``), for parameter sets of that
    image's size: what tuning calls (``values`` per candidate, in ``criteria.ids`` order,
    NaN where not measured)."""

    @property
    def criteria(self) -> Criteria: ...

    @property
    def output(self) -> OutputSpec: ...

    @property
    def fisheye(self) -> np.ndarray: ...

    def measure(self, params: IspParams) -> Measurements: ...

    def values(self, params: IspParams) -> np.ndarray: ...

    def __call__(self, params: IspParams) -> EcResult: ...


class FullEvaluator:
    """The full path for one image: every call remaps the whole label image
    (:func:`rvmsim.isp.process`) and measures it as ``rvmsim evaluate`` does.  Picklable."""

    path = EvaluationPath.FULL

    def __init__(self, image: FisheyeLabels, output: OutputSpec, criteria: Criteria):
        self.fisheye = np.ascontiguousarray(image.labels)
        self.output = output
        self.criteria = criteria
        self.context = scene_context(image.scene, image.camera, self.fisheye)

    def measure(self, params: IspParams) -> Measurements:
        """The raw measurements of one parameter set."""
        _, rvm = process(None, self.fisheye, params, self.output)
        assert rvm is not None
        return evaluate_rvm_labels(rvm, self.fisheye, params, self.output, self.criteria,
                                   context=self.context).measurements

    def values(self, params: IspParams) -> np.ndarray:
        """The measured values, (k,) in ``criteria.ids`` order, NaN where not measured."""
        return values_array(self.measure(params), self.criteria.ids)

    def __call__(self, params: IspParams) -> EcResult:
        return score(self.measure(params), self.criteria)


class RecordEvaluator:
    """One image judged at the RVM image of record while measuring at a search size: the
    values of ``search`` in units of record, or — for a candidate that passes or fails only
    near its limits (:func:`rvmsim.criteria.could_pass`) — the measurement of ``record``.
    Made by :func:`make_evaluator`; picklable.

    Convention: :attr:`output` is the search size (what sub-solves and windows use); the
    values, scores and pass flags are those of :attr:`record_output`.
    """

    def __init__(self, search: ImageEvaluator, record: ImageEvaluator):
        self.search, self.record = search, record
        self.criteria = search.criteria
        self.output = search.output
        self.record_output = record.output
        self.fisheye = search.fisheye
        self.path = getattr(search, "path", EvaluationPath.WINDOWED)
        self.rule = RecordRule(self.criteria, (search.output.width, search.output.height),
                               (record.output.width, record.output.height))

    def values(self, params: IspParams) -> np.ndarray:
        """The values of record, (k,) in ``criteria.ids`` order, NaN where not measured."""
        v = self.decided_values(self.search.values(params))
        return v if v is not None else self.record.values(params)

    def decided_values(self, search_values: np.ndarray) -> np.ndarray | None:
        """``search``'s values of a candidate in units of record when they decide its
        verdict (a clear fail), else None: the candidate is measured at the size of
        record."""
        v, undecided = self.rule.judge(search_values[None, :])
        return None if undecided[0] else v[0]

    def measure(self, params: IspParams) -> Measurements:
        """The measurements of record (a clear fail: the search size's, values converted)."""
        m = self.search.measure(params)
        v = self.decided_values(values_array(m, self.criteria.ids))
        if v is None:
            return self.record.measure(params)
        converted = {ec: None if np.isnan(x) else float(x) for ec, x in zip(self.criteria.ids, v)}
        return Measurements(converted, m.image_size, m.details)

    def __call__(self, params: IspParams) -> EcResult:
        return score(self.measure(params), self.criteria)


class SetEvaluator:
    """One ISP setting's ECs on every image of a :class:`FisheyeSet` (see the module
    docstring for :attr:`path`).  Made by :func:`make_evaluator`."""

    def __init__(self, images: FisheyeSet, output: OutputSpec, criteria: Criteria,
                 path: EvaluationPath, record: OutputSpec | None = None):
        self.images = images
        self.output = output
        self.criteria = criteria
        self.path = path
        #: The RVM image of record the verdicts refer to (default: ``output``).
        self.record_output = record or output
        self.rule = RecordRule(criteria, (output.width, output.height),
                               (self.record_output.width, self.record_output.height))
        self._table: RayTable | None = None

    def __call__(self, params: IspParams | Sequence[IspParams], *,
                 indices: Sequence[int] | None = None, progress: str | None = None) -> EcBatch:
        """Every EC on every image (or the images ``indices``).

        Parameters
        ----------
        params : IspParams or sequence of IspParams
            For the images' size: one setting for all, or one per image (per-car values).
        indices : sequence of int, optional
            The images to judge, in this order (default: all).
        progress : str, optional
            Show a progress bar with this description.

        Returns
        -------
        EcBatch
            One row per image (``values`` NaN where not measured; ``score``, ``all_passed``).
        """
        idx = list(range(len(self.images))) if indices is None else list(indices)
        per_image = [params] * len(idx) if isinstance(params, IspParams) else list(params)
        if len(per_image) != len(idx):
            raise ValueError(f"{len(per_image)} parameter sets for {len(idx)} images")
        values = np.full((len(idx), len(self.criteria.ids)), np.nan)
        bar = _bar(progress, len(idx))
        runs = _runs(per_image)
        chunks: list[tuple[list[int], IspParams | None]]
        if len(runs) * 4 <= max(len(idx), 4):  # few settings: one map for each one's images
            chunks = [(rows[a:a + _CHUNK], p) for rows, p in runs
                      for a in range(0, len(rows), _CHUNK)]
        else:  # one setting per image: in image order, so images sharing a render go together
            step = _CHUNK_EACH if self.path is EvaluationPath.RVM_PIXELS else _CHUNK
            chunks = [(list(range(a, min(a + step, len(idx)))), None)
                      for a in range(0, len(idx), step)]
        for chunk, setting in chunks:
            at = [idx[r] for r in chunk]
            values[chunk] = (self._values(setting, at, self.output) if setting is not None else
                             self._values_each([per_image[r] for r in chunk], at, self.output))
            if not self.rule.at_record:  # in units of record; near ones measured there
                values[chunk] = self._judged(values[chunk], setting,
                                             [per_image[r] for r in chunk], at)
            if bar is not None:
                bar.update(len(chunk))
        if bar is not None:
            bar.close()
        return score_batch(values, self.criteria)

    def _judged(self, values: np.ndarray, setting: IspParams | None, params: list[IspParams],
                indices: list[int]) -> np.ndarray:
        """Values of a chunk measured at the search size → the values of record (``setting``:
        the chunk's one setting, else one per image in ``params``)."""
        values, undecided = self.rule.judge(values)
        near = np.flatnonzero(undecided)
        if len(near):
            at = [indices[r] for r in near]
            values[near] = (self._values(setting, at, self.record_output) if setting is not None
                            else self._values_each([params[r] for r in near], at,
                                                   self.record_output))
        return values

    def _values_each(self, params: list[IspParams], indices: list[int], output: OutputSpec
                     ) -> np.ndarray:
        """The values of ``params[k]`` on image ``indices[k]`` (per-car values).  On the
        RVM-pixel path each image's pixels are made as the set reaches it, their rays
        looked up in the camera's (made once)."""
        crit = self.criteria
        if self.path is EvaluationPath.RVM_PIXELS:
            if self._table is None:
                self._table = ray_table(self.images.camera)
            table = self._table

            def pixels(k: int) -> RvmPixels:
                return rvm_pixels(self.images.camera, params[k], output, table=table)

            results = (measure_labels(labels, crit)
                       for labels in self.images.rvm_labels(pixels, indices))
        else:
            results = (FullEvaluator(im, output, crit).measure(params[k])
                       for k, im in enumerate(self.images.fisheye(indices)))
        return np.array([values_array(m, crit.ids) for m in results]).reshape(
            len(indices), len(crit.ids))

    def _values(self, params: IspParams, indices: list[int], output: OutputSpec) -> np.ndarray:
        """The values of one setting on ``indices``."""
        crit = self.criteria
        if self.path is EvaluationPath.RVM_PIXELS:
            pixels = rvm_pixels(self.images.camera, params, output)
            results = (measure_labels(labels, crit)
                       for labels in self.images.rvm_labels(pixels, indices))
        else:
            results = (FullEvaluator(im, output, crit).measure(params)
                       for im in self.images.fisheye(indices))
        return np.array([values_array(m, crit.ids) for m in results]).reshape(
            len(indices), len(crit.ids))


def _runs(per_image: list[IspParams]) -> list[tuple[list[int], IspParams]]:
    """Rows grouped by their parameter set (first-seen order): one map per setting."""
    groups: dict[IspParams, list[int]] = {}
    for r, p in enumerate(per_image):
        groups.setdefault(p, []).append(r)
    return [(rows, p) for p, rows in groups.items()]


def _bar(desc: str | None, total: int) -> ProgressBar | None:
    """A tqdm bar, or None without a description."""
    if desc is None:
        return None

    return progress_bar(total=total, desc=desc, unit="image", leave=False)
