"""The EC registry: what an evaluation criterion is, and where ECs come from.

An EC is an :class:`EcDefinition`: its id, name and unit, the label groups it reads, a
measure function, an annotate function, and its default acceptable range and sigmoid.  ECs
come from *plugins*: a Python module (or a ``.py`` file) with a module-level sequence
``ECS`` of definitions.  The paper's eleven ECs are the plugin :data:`BUILTIN_PLUGIN`
(``rvmsim/criteria/builtin.py``), written against the same public API a customer's plugin
uses; a criteria file names further plugins under ``plugins:`` (see docs/criteria.md).

A plugin is code the user names explicitly, loaded once per process
(:func:`load_plugin`).  Every definition loaded from a plugin remembers it
(:attr:`EcDefinition.plugin`) and pickles as (plugin, EC id): a worker process that unpickles
criteria loads the plugin again, also one loaded from a file path.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import importlib.util
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import CriteriaError
from .groups import LabelGroup, Window
from .hooks import InfeasibilityFn, StackParams, SubSolve
from .measure import (EcFailedError, LabelSource, Measurement, MeasureOptions, error_text,
                      measure_ecs, passes_through)
from .sigmoid import Criterion, Sigmoid
from .stack import LabelStack, StackMeasureFn, measure_stack_ecs
from ..isp import IspParams, OutputSpec

if TYPE_CHECKING:
    from .canvas import Canvas
    from .values import EcValue

__all__ = ["EcDefinition", "EC_IDS", "BUILTIN_PLUGIN", "ENTRY_POINT_GROUP", "MeasureFn",
           "AnnotateFn", "RegionsFn", "load_plugin", "resolve_plugin", "builtin_ecs",
           "ec_from_plugin", "checked_solve_value"]

#: The paper's eleven ECs, in the paper's order (section V).
EC_IDS: tuple[str, ...] = ("1-1", "1-2", "1-3", "1-4", "2-1", "2-2", "2-3", "2-4", "3-1",
                           "3-2", "4-1")
#: The plugin that defines the paper's eleven ECs.
BUILTIN_PLUGIN = "rvmsim.criteria.builtin"
#: Entry-point group under which installed packages may offer EC plugins by name.
ENTRY_POINT_GROUP = "rvmsim.criteria"

#: ``measure(source, options)`` → :class:`Measurement` (or the value alone: a number/None).
MeasureFn = Callable[[LabelSource, MeasureOptions], "Measurement | float | None"]
#: ``annotate(canvas, item, detail)``: draw one EC's measurement (``detail`` from measure:
#: :attr:`Measurement.detail`, of each EC's own type, so not typed here).
AnnotateFn = Callable[["Canvas", "EcValue", Any], None]
#: ``regions((H, W), options)`` → windows an EC reads besides its groups' windows.
RegionsFn = Callable[[tuple[int, int], MeasureOptions], Sequence[Window]]


@dataclass(frozen=True)
class EcDefinition:
    """One evaluation criterion (EC).

    Parameters
    ----------
    id : str
        Unique id, the key in criteria files and run stores (``"1-1"``, ``"acme-board-x"``);
        no spaces.
    name : str
        Short snake_case name for tables.
    unit : str
        Unit of the measured value (``"px"``, ``"%"``, ``"‰"``, ``""``).
    groups : tuple of LabelGroup
        The label groups the measure function asks windows of
        (:meth:`LabelSource.window`); the fast tuning evaluator remaps only those windows.
    measure : callable
        ``measure(source, options) -> Measurement`` (or a number or ``None``); must not raise
        or return NaN for a degenerate image: ``None`` means "cannot be measured".
    annotate : callable, optional
        ``annotate(canvas, item, detail)`` draws the measurement on the RVM image
        (:class:`rvmsim.criteria.Canvas`; ``item`` the scored :class:`EcValue`, ``detail``
        the measurement's detail).
    default_range : (low, high)
        Acceptable range when a criteria file does not set one (``None``: open side).
    default_sigmoid : Sigmoid, optional
        Score function when a criteria file does not set one.
    binary : bool
        The value is 0/1 and is its own score (criteria files cannot give it a sigmoid).
    description : str
        One line: what is measured.
    regions : callable, optional
        ``regions((H, W), options)`` → windows read besides the groups' windows (e.g. fixed
        image columns), so that the fast evaluator remaps them together.
    plugin : str
        Set when loaded (:func:`load_plugin`): the plugin's source, for pickling.
    parameters : dict
        Named numeric parameters of the measurement and their defaults (e.g. a limit), which
        a criteria file may change (``criteria: {id: {parameters: {name: value}}}``); the
        measure function reads them with ``options.parameter(id, name, default)``.  Stored
        as a tuple of ``(name, value)`` pairs (``dict(ec.parameters)``).
    uses_scene : bool
        The measure reads ``source.context`` and ``source.isp`` (the scene, its fisheye
        labels, the candidate's ISP map), not only the RVM labels: an evaluation must pass
        them, e.g. ``rvmsim robustness`` evaluates such criteria on each sample's full
        fisheye labels (:attr:`rvmsim.criteria.Criteria.uses_scene`).
    sub_solve : SubSolve, optional
        A closed-form sub-solve: the ISP parameter the EC pins for a given view and how to
        set it (:class:`rvmsim.criteria.SubSolve`); the ``cmaes-solved`` tuning strategy
        sets it per candidate (:class:`rvmsim.tune.EcSolver`).
    infeasibility : callable, optional
        ``infeasibility(context, criterion, options) -> (reason, short) | None``: why no ISP
        setting can pass the EC, read from the fisheye labels and the scene (``context`` a
        :class:`rvmsim.criteria.SceneContext`, ``criterion`` the EC's criterion, texts
        without the EC id); a design sweep then calls the point ``infeasible``
        (:func:`rvmsim.batch.infeasible_ecs`).
    pixel_axis : {"x", "y", ""}
        For a ``"px"`` EC: the image axis its value is a length along (``"x"``: a width or
        column offset, ``"y"``: a height); ``""``: both (a length in any direction).  A value
        measured at a search size is converted to the RVM image of record with that axis's
        scale (:mod:`rvmsim.criteria.record`).  Ignored for other units.
    needs : tuple of tuple of int
        What the scene must hold for the EC to be measurable: label id sets, each needing
        at least one of its labels (``((patch F,), (patch G,))``: both patches).  A scene
        whose settings leave a whole set out (an object, the guidelines or the board
        disabled) cannot support the EC (:func:`rvmsim.criteria.unsupported_ecs`); ():
        the labels of a :class:`~rvmsim.criteria.LabelsAbsent` feasibility reason, else
        nothing.
    measure_stack : callable, optional
        ``measure_stack(stack, options)`` → one Measurement (or value) per image of a
        :class:`rvmsim.criteria.LabelStack`: the measurement on K images at once, image for
        image exactly what ``measure`` gives on that image alone (a speed-up for robust
        tuning, which judges each candidate on many images; :mod:`rvmsim.criteria.stack`).
    """

    id: str
    name: str
    unit: str
    groups: tuple[LabelGroup, ...]
    measure: MeasureFn
    annotate: AnnotateFn | None = None
    default_range: tuple[float | None, float | None] = (None, None)
    default_sigmoid: Sigmoid | None = None
    binary: bool = False
    description: str = ""
    regions: RegionsFn | None = None
    plugin: str = ""
    parameters: Mapping[str, float] | tuple[tuple[str, float], ...] = ()
    uses_scene: bool = False
    sub_solve: SubSolve | None = None
    infeasibility: InfeasibilityFn | None = None
    pixel_axis: str = ""
    needs: tuple[tuple[int, ...], ...] = ()
    measure_stack: StackMeasureFn | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id or any(c.isspace() for c in self.id):
            raise ValueError(f"EC id must be a non-empty string without spaces, got {self.id!r}")
        for key in ("name", "unit", "description", "plugin"):
            if not isinstance(getattr(self, key), str):
                raise TypeError(f"EC {self.id!r}: {key} must be a string")
        groups = tuple(self.groups) if isinstance(self.groups, (list, tuple)) else None
        if groups is None or not all(isinstance(g, LabelGroup) for g in groups):
            raise TypeError(f"EC {self.id!r}: groups must be a tuple of LabelGroup")
        object.__setattr__(self, "groups", groups)
        for key in ("measure", "annotate", "regions", "infeasibility", "measure_stack"):
            fn = getattr(self, key)
            if not callable(fn) and not (fn is None and key != "measure"):
                raise TypeError(f"EC {self.id!r}: {key} must be a function")
        if self.pixel_axis not in ("x", "y", ""):
            raise ValueError(f"EC {self.id!r}: pixel_axis must be 'x', 'y' or '', got "
                             f"{self.pixel_axis!r}")
        try:
            needs = tuple(tuple(int(i) for i in ids) for ids in self.needs)
        except (TypeError, ValueError):
            raise TypeError(f"EC {self.id!r}: needs must be a tuple of label id tuples") from None
        object.__setattr__(self, "needs", needs)
        if self.sub_solve is not None and not isinstance(self.sub_solve, SubSolve):
            raise TypeError(f"EC {self.id!r}: sub_solve must be an rvmsim.criteria.SubSolve "
                            "or None")
        self._check_defaults()

    def _check_defaults(self) -> None:
        rng = self.default_range
        if not isinstance(rng, (list, tuple)) or len(rng) != 2 or not all(
                x is None or (isinstance(x, (int, float)) and not math.isnan(x)) for x in rng):
            raise TypeError(f"EC {self.id!r}: default_range must be (low, high), numbers or None")
        if rng[0] is not None and rng[1] is not None and rng[0] > rng[1]:
            raise ValueError(f"EC {self.id!r}: default_range needs low <= high")
        object.__setattr__(self, "default_range",
                           tuple(None if x is None else float(x) for x in rng))
        if self.default_sigmoid is not None and not isinstance(self.default_sigmoid, Sigmoid):
            raise TypeError(f"EC {self.id!r}: default_sigmoid must be a Sigmoid or None")
        if not isinstance(self.binary, bool):
            raise TypeError(f"EC {self.id!r}: binary must be True or False")
        params = self.parameters
        pairs = list(params.items()) if isinstance(params, Mapping) else list(params)
        if not all(isinstance(p, tuple) and len(p) == 2 and isinstance(p[0], str)
                   and isinstance(p[1], (int, float)) and math.isfinite(p[1]) for p in pairs):
            raise TypeError(f"EC {self.id!r}: parameters must map names to finite numbers")
        # a tuple of (name, value) pairs: the definition stays hashable
        object.__setattr__(self, "parameters", tuple((k, float(v)) for k, v in pairs))

    def default_criterion(self) -> Criterion:
        """The EC's :class:`Criterion` when a criteria file changes nothing about it."""
        low, high = self.default_range
        return Criterion(self.id, low, high, None if self.binary else self.default_sigmoid)

    def __reduce__(self) -> tuple[Callable[..., EcDefinition], tuple[object, ...]]:
        # By reference when loaded from a plugin: the functions of a plugin loaded from a file
        # path are not importable by name in another process, the plugin is.
        if self.plugin:
            return (ec_from_plugin, (self.plugin, self.id))
        return (type(self), tuple(getattr(self, f.name) for f in dataclasses.fields(self)))


# ---------------------------------------------------------------------------- plugins
#: Plugins loaded in this process: source → its ECs (like ``sys.modules``, a cache of code
#: already imported; a plugin is loaded once per process).
_LOADED: dict[str, tuple[EcDefinition, ...]] = {}


def resolve_plugin(entry: str, base_dir: Path) -> str:
    """A ``plugins:`` entry of a criteria file → the plugin's source for :func:`load_plugin`.

    ``something.py`` (or any entry with a path separator) is a file, relative to
    ``base_dir`` (the criteria file's folder) unless absolute; a name an installed package
    offers in the entry-point group :data:`ENTRY_POINT_GROUP` is that entry point's module;
    anything else is an importable module name (``acme_rvm.criteria``).
    """
    if entry.endswith(".py") or "/" in entry or "\\" in entry:
        path = Path(entry).expanduser()
        return str((path if path.is_absolute() else base_dir / path).resolve())
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        if ep.name == entry:
            return str(ep.value)
    return entry


def builtin_ecs() -> tuple[EcDefinition, ...]:
    """The paper's eleven ECs (:data:`EC_IDS` order)."""
    return load_plugin(BUILTIN_PLUGIN)


def ec_from_plugin(source: str, ec_id: str) -> EcDefinition:
    """The EC ``ec_id`` of a plugin (loading the plugin if needed): how ECs unpickle."""
    for ec in load_plugin(source):
        if ec.id == ec_id:
            return ec
    raise CriteriaError(source, "ECS", f"the plugin has no EC {ec_id!r}")


def load_plugin(source: str) -> tuple[EcDefinition, ...]:
    """The ECs of a plugin (its module-level ``ECS``), each checked on an empty image.

    Parameters
    ----------
    source : str
        An absolute ``.py`` path, a module name, or ``module:attribute`` (an object with an
        ``ECS`` attribute); see :func:`resolve_plugin`.

    Raises
    ------
    CriteriaError
        One line naming the plugin: it cannot be imported, has no ``ECS``, or one of its ECs
        breaks the API (bad fields, or its measure function fails on an empty image).
    """
    ecs = _LOADED.get(source)
    if ecs is None:
        obj = _import(source)
        found = _attribute(source, obj, "ECS")
        if not isinstance(found, (list, tuple)) or not found:
            raise CriteriaError(source, "ECS", "a plugin needs a module-level ECS: a non-empty "
                                "list of rvmsim.criteria.EcDefinition")
        if not all(isinstance(ec, EcDefinition) for ec in found):
            raise CriteriaError(source, "ECS", "every item must be an rvmsim.criteria.EcDefinition")
        ids = [ec.id for ec in found]
        if len(set(ids)) != len(ids):
            raise CriteriaError(source, "ECS", "two ECs have the same id")
        ecs = tuple(dataclasses.replace(ec, plugin=source) for ec in found)
        for ec in ecs:
            _probe(ec, source)
        _LOADED[source] = ecs
    return ecs


#: Plugin modules of the bundled regulations under the names criteria files written before
#: they moved to :mod:`rvmsim.regulations` (2026-12-05) give them: such files, and the runs
#: that recorded them, still load.
MOVED_PLUGINS: dict[str, str] = {"rvmsim.criteria.fmvss111": "rvmsim.regulations.fmvss111.ecs",
                                 "rvmsim.criteria.unr158": "rvmsim.regulations.unr158.ecs",
                                 "rvmsim.criteria.jp": "rvmsim.regulations.jp.ecs"}


def _import(source: str) -> object:
    if source.endswith(".py"):
        return _import_file(Path(source))
    module_name, _, attr = source.partition(":")
    module_name = MOVED_PLUGINS.get(module_name, module_name)
    try:
        obj: object = importlib.import_module(module_name)
    except ImportError as err:
        raise CriteriaError(source, "", f"cannot import the plugin ({err})") from None
    except BaseException as err:  # noqa: BLE001 - the plugin's own code failed on import
        raise _import_failure(source, err) from None
    for part in filter(None, attr.split(".")):
        obj = _attribute(source, obj, part)
        if obj is None:
            raise CriteriaError(source, "", f"the module has no attribute {part!r}")
    return obj


def _attribute(source: str, obj: object, name: str) -> object:
    """``obj.name`` of a plugin, None when it has none; what the plugin's own code raises
    while giving it (a module ``__getattr__``, a property) is one line naming the plugin."""
    try:
        return getattr(obj, name, None)
    except BaseException as err:  # noqa: BLE001 - the plugin's own code failed
        if isinstance(err, KeyboardInterrupt):
            raise
        what = (f"it called sys.exit({err.code!r})" if isinstance(err, SystemExit)
                else _what(err))
        raise CriteriaError(source, name, f"reading the plugin's {name} failed ({what})"
                            ) from None


def _import_failure(source: str, err: BaseException) -> BaseException:
    """What a plugin's failure on import becomes: ``err`` itself for a Ctrl-C or SIGTERM
    (:func:`~.measure.passes_through`), else a :class:`CriteriaError` naming the plugin, also
    for ``sys.exit`` (a ``SystemExit``, which would otherwise end rvmsim with the plugin's
    status, 0 included) and any other ``BaseException``.  ``os._exit`` ends the process
    below Python and cannot be caught."""
    if isinstance(err, KeyboardInterrupt):
        return err
    if isinstance(err, SystemExit):
        what = f"it called sys.exit({err.code!r})"
    else:
        what = _what(err)
    return CriteriaError(source, "", f"the plugin failed on import ({what})")


def _import_file(path: Path) -> object:
    if not path.is_file():
        raise CriteriaError(str(path), "", "plugin file not found")
    digest = hashlib.sha1(str(path).encode()).hexdigest()[:12]
    name = f"rvmsim_criteria_plugin_{path.stem}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise CriteriaError(str(path), "", "not a loadable Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and pickling look the module up by name
    try:
        spec.loader.exec_module(module)
    except BaseException as err:  # noqa: BLE001 - the plugin's own code failed on import
        del sys.modules[name]
        raise _import_failure(str(path), err) from None
    return module


def _probe(ec: EcDefinition, source: str) -> None:
    """Run an EC on an empty 8×8 image: catches API breaks when the plugin loads rather than
    in the middle of a tuning run."""
    src = LabelSource(np.zeros((8, 8), np.uint8), ec.groups)
    try:
        alone = measure_ecs(src, [ec], MeasureOptions()).values[ec.id]
        if ec.measure_stack is not None:
            stack = LabelStack(np.zeros((8, 8, 2), np.uint8), ec.groups)
            each = [m.values[ec.id] for m in measure_stack_ecs(stack, [ec], MeasureOptions())]
            if each != [alone, alone]:
                raise TypeError(f"measure_stack gives {each} where measure gives {alone} "
                                "on each image")
        if ec.regions is not None:
            wins = [tuple(int(v) for v in win) for win in ec.regions((8, 8), MeasureOptions())]
            if not all(len(win) == 4 for win in wins):
                raise TypeError("regions must return (x0, y0, x1, y1) windows")
    except EcFailedError as err:  # its measure (measure_ecs names the failure so)
        raise CriteriaError(source, ec.id, f"the EC fails on an empty 8x8 image ({err.what})"
                            ) from None
    except BaseException as err:  # noqa: BLE001 - any failure of the plugin's code is reported
        if passes_through(err, ""):
            raise
        raise CriteriaError(source, ec.id, f"the EC fails on an empty 8x8 image ({_what(err)})"
                            ) from None
    if ec.sub_solve is not None:
        _probe_sub_solve(ec, ec.sub_solve, source)


def _probe_sub_solve(ec: EcDefinition, hook: SubSolve, source: str) -> None:
    """Run a sub-solve's target on the EC's default criterion and its solve on a small
    square of plane points: both must return a finite number or None."""

    square = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])
    try:
        target = hook.target(ec.default_criterion())
        checked_solve_value(ec, "target", target)
        value = hook.solve(square, IspParams(), OutputSpec(64, 36),
                           0.0 if target is None else float(target))
        if hook.solve_stack is not None:  # two images of the square: what solve gives
            each = np.asarray(hook.solve_stack(
                np.concatenate([square, square]), np.array([0, 4, 8]),
                StackParams(IspParams(), {}, 2), OutputSpec(64, 36),
                0.0 if target is None else float(target)), dtype=np.float64).reshape(-1)
            alone = math.nan if value is None else float(value)
            if not np.array_equal(each, [alone, alone], equal_nan=True):
                raise TypeError(f"solve_stack gives {each.tolist()} where solve gives "
                                f"{value!r} for each image")
    except BaseException as err:  # noqa: BLE001 - any failure of the plugin's code is reported
        if passes_through(err, ""):
            raise
        raise CriteriaError(source, ec.id, f"the EC's sub-solve fails on a square of plane "
                                           f"points ({_what(err)})") from None
    checked_solve_value(ec, "solve", value)


def checked_solve_value(ec: EcDefinition, what: str, value: object) -> float | None:
    """A sub-solve's ``target`` or ``solve`` result as a float (None stays None).

    Raises
    ------
    CriteriaError
        It is not a finite number or None (a plugin that breaks the API)."""
    if value is None:
        return None
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        x = float(value)
        if math.isfinite(x):
            return x
    raise CriteriaError(ec.plugin or "<ec>", ec.id, f"the sub-solve's {what} returned "
                        f"{value!r} (expected a finite number or None)")


def _what(err: BaseException) -> str:
    return error_text(err)
