"""Reading label pixels for the ECs: label sources, options, measurement results, helpers.

An EC's measure function receives a :class:`LabelSource` and the criteria's
:class:`MeasureOptions` and returns a :class:`Measurement` (its value, and whatever geometry
its annotate function draws).  A source gives the window of each declared label group and the
label pixels of any window; :class:`LabelSource` reads them from a whole RVM label image, the
fast tuning evaluator remaps only the windows it is asked for.  Both give the same pixels, so
a measure function written against this interface gives the same value either way.

Conventions: pixel centres at integer (column, row); windows ``(x0, y0, x1, y1)`` in output
px with ``x1``/``y1`` exclusive.  A measurement that cannot be made (its object is not in the
image) has value ``None``; a measure function never raises or returns NaN for a degenerate
image (an empty, tiny or single-label one).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol, TypeVar

import cv2
import numpy as np

from ..errors import CriteriaError
from .groups import LabelGroup, Window, group_windows

if TYPE_CHECKING:
    from ..scene import Display
    from .context import IspView, SceneContext

__all__ = ["MeasureOptions", "Measurement", "Measurements", "LabelSource", "measure_ecs",
           "EcFailedError", "error_text", "passes_through", "call_ec", "label_mask", "count_label",
           "bounding_box", "offset", "measurement_of", "image_name", "MeasuredEc", "PixelReads"]

T = TypeVar("T")

#: Plugins whose module name starts so are rvmsim's own (the paper's ECs, the markets').
BUNDLED_PLUGIN_PREFIX = "rvmsim."


@dataclass(frozen=True)
class MeasureOptions:
    """Measurement options of a criteria file (the same for every EC that uses them).

    Parameters
    ----------
    upper_region_fraction : float
        Top fraction of the image that counts as its upper region (EC 2-4 keeps it free of
        body parts; groups with ``upper_region=True`` are read there only).
    edge_columns : int
        Columns averaged for each bumper height (t_l, t_r at the edges, t_c centred).
    display : Display, optional
        The criteria file's ``display`` section (a scene's own wins:
        :meth:`rvmsim.criteria.SceneContext.display`).
    parameters : tuple
        Per EC, its named parameters with the criteria file's changes applied:
        ``((ec_id, ((name, value), ...)), ...)``; read them with :meth:`parameter`.
    """

    upper_region_fraction: float = 0.5
    edge_columns: int = 4
    display: Display | None = None
    parameters: tuple[tuple[str, tuple[tuple[str, float], ...]], ...] = ()

    def upper_rows(self, height: int) -> int:
        """Rows of the upper region of an image ``height`` px high."""
        return int(round(self.upper_region_fraction * height))

    def parameter(self, ec_id: str, name: str, default: float) -> float:
        """EC ``ec_id``'s parameter ``name`` (:attr:`~.registry.EcDefinition.parameters`),
        ``default`` when the options do not carry it (e.g. the load-time probe)."""
        for ec, values in self.parameters:
            if ec == ec_id:
                return dict(values).get(name, default)
        return default


class Measurement(NamedTuple):
    """What an EC's measure function returns (an immutable record; a named tuple because one
    is made per EC per candidate).

    Attributes
    ----------
    value : float or None
        The measured value in the EC's unit; ``None`` when it cannot be measured (scores 0,
        fails).
    detail : object, optional
        Anything the EC's annotate function needs to draw the measurement (output px).
    """

    value: float | None
    detail: object = None


@dataclass(frozen=True)
class Measurements:
    """Raw measurements of one RVM label image: per EC id (evaluation order) its value and
    detail (:attr:`Measurement.detail`, for the annotation); geometry in output px."""

    values: dict[str, float | None]
    image_size: tuple[int, int]  # (W, H) px
    details: dict[str, object] = field(default_factory=dict)


class PixelReads:
    """What label sources and stacks share: windows of ``labels`` ((H, W) uint8, or
    (H, W, K) for K images) and work shared between ECs."""

    labels: np.ndarray
    shape: tuple[int, int]
    _shared: dict[Hashable, Any]

    def pixels(self, win: Window) -> np.ndarray:
        """The label pixels of a window, (y1 − y0, x1 − x0) uint8 (and K images last, for
        a stack)."""
        x0, y0, x1, y1 = win
        return self.labels[y0:y1, x0:x1]

    def columns(self, x0: int, x1: int) -> np.ndarray:
        """Every row of columns [x0, x1): (H, x1 − x0) uint8 (and K images last)."""
        return self.pixels((x0, 0, x1, self.shape[0]))

    def shared(self, key: Hashable, compute: Callable[[], T]) -> T:
        """``compute()``, once per source or stack: for work several ECs share (e.g. the
        bumper heights of ECs 2-1 … 2-3).  ``key`` must name the work and its options."""
        try:
            return self._shared[key]
        except KeyError:
            out = self._shared[key] = compute()
            return out


class LabelSource(PixelReads):
    """The label pixels measurements read: here a whole RVM label image.

    Parameters
    ----------
    labels : (H, W) uint8
        RVM label image (ids from :mod:`rvmsim.labels`).
    groups : sequence of LabelGroup, optional
        The groups measurements will ask windows of (distinct names,
        :func:`rvmsim.criteria.groups.unique_groups`), found at once in one pass
        (:func:`rvmsim.criteria.group_windows`); asking for another group is an error, so an
        EC that reads a group it does not declare fails here as it would in the fast
        evaluator.  Default: any group, each found when first asked for.
    context : SceneContext, optional
        The scene the image shows (:attr:`context`; :mod:`rvmsim.criteria.context`).
    isp : IspView, optional
        The ISP map that made the image (:attr:`isp`).

    Attributes
    ----------
    context : SceneContext or None
        Per scene: the scene, camera and fisheye label image, and a per-scene cache.
    isp : IspView or None
        Per candidate: exact point mappings of its ISP map (fisheye px ↔ RVM px).
    """

    def __init__(self, labels: np.ndarray, groups: Sequence[LabelGroup] | None = None, *,
                 context: SceneContext | None = None, isp: IspView | None = None):
        labels = np.asarray(labels)
        if labels.ndim != 2 or labels.dtype != np.uint8:
            raise TypeError(f"labels must be a 2-D uint8 image, got {labels.dtype} {labels.shape}")
        self.labels = np.ascontiguousarray(labels)
        self.shape: tuple[int, int] = (int(labels.shape[0]), int(labels.shape[1]))
        self._declared = groups is not None
        self._windows = {} if groups is None else group_windows(self.labels, groups)
        self._shared: dict[Hashable, Any] = {}  # each value of its caller's own type
        self.context = context
        self.isp = isp

    def window(self, group: LabelGroup | str) -> Window:
        """A window that holds every pixel of ``group`` and the pixels next to them."""
        name = group if isinstance(group, str) else group.name
        win = self._windows.get(name)
        if win is None:
            if self._declared or isinstance(group, str):
                raise KeyError(f"label group {name!r} is not declared by the ECs measured")
            win = self._windows[name] = group_windows(self.labels, [group])[name]
        return win



class MeasuredEc(Protocol):
    """What :func:`measure_ecs` needs of an EC (an :class:`~.registry.EcDefinition` is
    one): its id, the plugin that defines it (for messages) and its measure function."""

    @property
    def id(self) -> str: ...

    @property
    def plugin(self) -> str: ...

    @property
    def measure(self) -> Callable[[LabelSource, MeasureOptions], object]: ...


def measure_ecs(src: LabelSource, ecs: Sequence[MeasuredEc],
                options: MeasureOptions) -> Measurements:
    """Run each EC's measure function on one source.

    Raises
    ------
    CriteriaError
        An EC's measure function returned something else than a :class:`Measurement`, a
        number or ``None`` (a plugin that breaks the API).
    """
    h, w = src.shape
    values: dict[str, float | None] = {}
    details: dict[str, object] = {}
    for ec in ecs:
        try:
            value, detail = measurement_of(ec, ec.measure(src, options))
        except BaseException as err:  # noqa: BLE001 - the EC's own code: see passes_through
            if passes_through(err, ec.plugin):
                raise
            raise EcFailedError(ec.plugin or "<ec>", ec.id, "measure", image_name(src),
                                error_text(err)) from None
        values[ec.id] = value
        details[ec.id] = detail
    return Measurements(values, (w, h), details)


def measurement_of(ec: MeasuredEc, m: object) -> tuple[float | None, object]:
    """(value, detail) of what an EC's measure function returned: a :class:`Measurement`,
    or the value alone; the value a plain float, or None for NaN or nothing.

    Raises
    ------
    CriteriaError
        Something else than a Measurement, a number or None."""
    value, detail = (m.value, m.detail) if isinstance(m, Measurement) else (m, None)
    if type(value) is not float or value != value:  # not a plain float, or NaN
        value = _checked_value(ec, value)
    return value, detail


class EcFailedError(CriteriaError):
    """An EC's own code (a plugin's) raised: one line naming the plugin, the EC, what of it
    failed and on which image.

    Parameters
    ----------
    plugin : str
        The plugin that defines the EC (its file or module).
    ec_id : str
        The EC.
    part : str
        What of the EC failed: ``"measure"``, ``"annotate"``, ``"regions"``, ….
    image : str
        The image it failed on (:func:`image_name`).
    what : str
        The error (:func:`error_text`).

    Notes
    -----
    Pickles by its parameters, so that a worker process's failure reaches the parent whole.
    """

    def __init__(self, plugin: str, ec_id: str, part: str, image: str, what: str):
        self.plugin, self.ec_id, self.part, self.image, self.what = (
            plugin, ec_id, part, image, what)
        super().__init__(plugin, f"EC {ec_id}", f"the plugin's {part} failed on {image} "
                                                f"({what})")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        return (type(self), (self.plugin, self.ec_id, self.part, self.image, self.what))

    def on(self, image: str) -> EcFailedError:
        """The same failure, naming the image as ``image`` (a caller that knows more of it,
        e.g. its scene)."""
        return type(self)(self.plugin, self.ec_id, self.part, image, self.what)


def passes_through(err: BaseException, plugin: str) -> bool:
    """Whether an exception raised by an EC's code goes on as it is rather than becoming an
    :class:`EcFailedError`: a Ctrl-C or SIGTERM (``KeyboardInterrupt`` and its
    subclasses) stops the command, a :class:`CriteriaError` already names the plugin, and
    rvmsim's own ECs (plugins ``rvmsim.…``) failing is a bug of rvmsim, reported with its
    traceback.  Anything else a plugin raises, also ``SystemExit`` and other
    ``BaseException`` subclasses, is the plugin's failure."""
    return (isinstance(err, (KeyboardInterrupt, CriteriaError))
            or plugin.startswith(BUNDLED_PLUGIN_PREFIX))


def call_ec(ec: MeasuredEc, part: str, image: str, fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)``, a function of ``ec`` (its ``part``: ``"annotate"``, ``"regions"``, …)
    run on ``image`` (for the message); what it raises becomes an :class:`EcFailedError`
    unless it :func:`passes_through`."""
    try:
        return fn(*args)
    except BaseException as err:  # noqa: BLE001 - the EC's own code: see passes_through
        if passes_through(err, ec.plugin):
            raise
        raise EcFailedError(ec.plugin or "<ec>", ec.id, part, image, error_text(err)) from None


def error_text(err: BaseException) -> str:
    """``Type: first line of the message`` (or the type alone), at most 200 characters."""
    text = str(err).strip().splitlines()[0] if str(err).strip() else ""
    return (f"{type(err).__name__}: {text}" if text else type(err).__name__)[:200]


def image_name(src: LabelSource) -> str:
    """The image a source reads, for messages: ``the 320x180 RVM image of scene.yaml`` (its
    scene's file when the source knows it)."""
    h, w = src.shape
    scene = getattr(getattr(src, "context", None), "scene", None)
    where = getattr(scene, "source", "") or ""
    return f"the {w}x{h} RVM image" + (f" of {where}" if where and where != "<dict>" else "")


def _checked_value(ec: MeasuredEc, value: object) -> float | None:
    if value is None:
        return None
    if isinstance(value, (bool, int, float, np.integer, np.floating)):
        x = float(value)
        return None if math.isnan(x) else x
    raise CriteriaError(ec.plugin or "<ec>", ec.id,
                        f"measure returned {type(value).__name__} (expected a Measurement, "
                        "a number or None)")


# ---------------------------------------------------------------------------- helpers
def label_mask(sub: np.ndarray, label: int) -> np.ndarray:
    """255 where ``sub == label``, else 0 (uint8, same shape)."""

    if sub.size <= 1:  # OpenCV takes a 1×1 image for a scalar
        return (sub == label).astype(np.uint8) * 255
    return cv2.compare(sub, label, cv2.CMP_EQ)  # type: ignore[call-overload]  # scalar operand


def count_label(sub: np.ndarray, label: int) -> int:
    """Pixels of ``sub`` equal to ``label``."""

    return 0 if sub.size == 0 else int(cv2.countNonZero(label_mask(sub, label)))


def bounding_box(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """``(x, y, w, h)`` px of the non-zero pixels of a uint8 mask, ``None`` if there are none."""

    if mask.size == 0:
        return None
    x, y, w, h = cv2.boundingRect(mask)
    return None if w == 0 else (int(x), int(y), int(w), int(h))


def offset(box: tuple[int, int, int, int], win: Window) -> tuple[int, int, int, int]:
    """A box found in a window's pixels, in image px."""
    return (box[0] + win[0], box[1] + win[1], box[2], box[3])

