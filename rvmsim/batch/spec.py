"""The sweep file: loading and checking it, its axes, and the design points they span.

Sweep file (YAML)::
    name: Vehicle A mount study
    base_scene: ../scenes/vehicle_a.yaml      # relative to the sweep file
    axes:                                      # in order; the table and maps follow it
      camera_height_m: [0.9, 1.0, 1.1]         # a named axis (see AXES) ...
      pitch_deg: {start: 25, stop: 40, num: 4} # ... lists or ranges (stop included) ...
      vehicle.bumper.top: [0.7, 0.8]           # ... or any scene key by its dotted path
    tune:
      strategy: cmaes-solved                   # any strategy of `rvmsim tune`
      budget: 1500
      seed: 0
      config: {output: {size: [640, 360]}}     # a tuning config (as `rvmsim tune --config`)
      criteria: my_criteria.yaml               # optional, relative to the sweep file
      # markets: [fmvss111-full, unr158]       # or: pass every market (not with criteria)
      recheck: {rounds: 3, budget_factor: 2, neighbours: 4}   # re-check of failing points
    map: [camera_height_m, pitch_deg]          # the feasibility map's x and y axes
    sensitivity: true
    robustness: {samples: 64, seed: 0}         # each point's yield (base scene's variation)

Each combination of axis values is a :class:`DesignPoint` (:func:`point_scene_doc`: its scene
and tuning config); problems are one-line errors (:class:`~rvmsim.errors.SweepFileError`).
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .._io import FilePathText, KeyPath, input_error_from_validation, key_lines, parse_yaml_mapping, read_text
from ..criteria import Criteria, bundled_criteria_text, criteria_from_text, default_criteria
from ..errors import CriteriaError, InputFileError, RvmsimError, SweepFileError
from ..scene import Scene, absolute_mesh_paths, read_scene_document, scene_from_dict
from ..search import DEFAULT_STRATEGY, STRATEGIES, TuningConfig
from .markets import market_ec_ids, markets_fingerprint, sweep_markets
from .axes import AXES, MAX_AXIS_VALUES, POSITION_AXES, expand_axis, sweep_error as _error
from .yields import YieldModel, YieldSettings

__all__ = ["AXES", "SweepSpec", "DesignPoint", "RecheckSettings", "load_sweep",
           "design_points", "point_scene_doc", "MAX_AXIS_VALUES", "MAX_SWEEP_POINTS",
           "MAX_RECHECK_ROUNDS"]

#: Most design points of a sweep (each one is a tuning run) unless ``allow_large``
#: (``rvmsim sweep --allow-large``).
MAX_SWEEP_POINTS = 1000
#: Most re-check rounds of a sweep (``tune.recheck.rounds``).
MAX_RECHECK_ROUNDS = 20



# ---------------------------------------------------------------------------- the file
class _Recheck(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)
    rounds: int = Field(default=3, ge=0, le=MAX_RECHECK_ROUNDS)
    budget_factor: float = Field(default=2.0, ge=1.0, le=100.0)
    neighbours: int = Field(default=4, ge=0, le=26)


class _Tune(BaseModel):
    model_config = ConfigDict(extra="forbid")
    strategy: str = DEFAULT_STRATEGY
    budget: int | None = Field(default=1500, ge=1)
    seed: int = 0
    config: dict[str, Any] = {}
    criteria: str | None = None
    markets: list[str] | None = None
    recheck: _Recheck = _Recheck()


@dataclass(frozen=True)
class RecheckSettings:
    """How a sweep re-checks the points its first pass did not find passing
    (``tune.recheck``; see :mod:`rvmsim.batch.recheck`).

    ``rounds``: most re-check rounds (0: none); ``budget_factor``: each re-check's budget
    as a multiple of ``tune.budget``; ``neighbours``: most neighbouring optima a re-check
    starts from (best first), besides the point's own best.
    """

    rounds: int = 3
    budget_factor: float = 2.0
    neighbours: int = 4


class _SweepFile(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = "sweep"
    base_scene: FilePathText
    axes: dict[str, Any] = Field(min_length=1)  # lists or ranges: see expand_axis
    tune: _Tune = _Tune()
    map: tuple[str, str] | None = None
    sensitivity: bool = True
    robustness: YieldModel = YieldModel()


@dataclass(frozen=True)
class SweepSpec:
    """A loaded sweep file.  ``axes`` keeps the file's order; every value list is expanded.

    ``criteria_doc`` is the criteria file's text (None: the default criteria);
    ``robustness``: the yield settings; ``has_variation``: some design point's scene has a
    ``variation`` section (those points get a yield unless ``robustness.samples`` is 0);
    ``markets``: the specs of ``tune.markets`` (:attr:`rvmsim.markets.Market.spec`; empty:
    one criteria set), every point tuned to pass all of them (:mod:`rvmsim.batch.markets`);
    ``lines`` maps the file's key paths to their lines, for error messages.
    ``base_doc``, ``config`` (``tune.config``) and the axis values are as the YAML gives them.
    """

    name: str
    source: str
    base_scene: Path
    base_doc: dict[str, Any]
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    strategy: str
    budget: int | None
    seed: int
    config: dict[str, Any]
    criteria_doc: str | None
    map_axes: tuple[str, str] | None
    sensitivity: bool
    criteria_source: str = "sweep criteria"
    recheck: RecheckSettings = RecheckSettings()
    robustness: YieldSettings = YieldSettings()
    has_variation: bool = False
    markets: tuple[str, ...] = ()
    lines: Mapping[KeyPath, int] = field(default_factory=dict, compare=False, repr=False)

    def fingerprint(self) -> str:
        """Hash of what a design point's result depends on besides its axis values."""
        h = hashlib.sha256()
        parts: list[Any] = [self.base_doc, self.strategy, self.budget, self.seed, self.config,
                 self.criteria_doc, self.sensitivity]
        if self.markets:  # kept out otherwise: stores made before markets still resume
            parts.append(markets_fingerprint(self.markets))
        h.update(json.dumps(parts, sort_keys=True, default=str).encode())
        for path in absolute_mesh_paths(copy.deepcopy(self.base_doc), self.base_scene.parent):
            if path.is_file():
                _hash_file(h.update, path)
            else:
                h.update(b"?")
        return h.hexdigest()[:20]

    def recheck_fingerprint(self) -> str:
        """Hash of the re-check settings (kept apart from :meth:`fingerprint`, so a store
        made before re-checks existed still resumes)."""
        r = self.recheck
        text = json.dumps([r.rounds, r.budget_factor, r.neighbours])
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def yield_fingerprint(self) -> str:
        """Hash of the yield settings, or of "no yield" when no point gets one (kept apart
        from :meth:`fingerprint`, so a store made before yields existed still resumes)."""
        r = self.robustness
        text = json.dumps([r.samples, r.seed] if self.has_variation and r.samples else "-")
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def ec_ids(self) -> tuple[str, ...]:
        """The EC ids of the results' EC columns: the criteria's, or every market's (the
        first market's first, each id once)."""
        return market_ec_ids(self.markets) if self.markets else self.criteria().ids

    def criteria(self) -> Criteria:
        """The criteria every design point is judged by (a markets sweep: the defaults; each
        market has its own, :func:`rvmsim.markets.market_criteria`)."""
        if self.criteria_doc is None:
            return default_criteria()
        return criteria_from_text(self.criteria_doc, self.criteria_source)

    def error(self, key: str, message: str, at: KeyPath | None = None) -> SweepFileError:
        """A :class:`SweepFileError` at ``key`` (dotted) of this sweep file; see
        :func:`_error`."""
        return _error(self.source, self.lines, key, message, at)


def _hash_file(update: Callable[[bytes], None], path: Path) -> None:
    """Feed ``path``'s bytes to a hash's ``update`` in 1 MiB pieces (a mesh file may be large)."""
    with path.open("rb") as f:
        for piece in iter(lambda: f.read(1 << 20), b""):
            update(piece)


def _point_count(axes: tuple[tuple[str, tuple[object, ...]], ...], allow_large: bool,
                 source: str, lines: Mapping[KeyPath, int]) -> int:
    """The number of design points the axes span, refused over :data:`MAX_SWEEP_POINTS`
    unless ``allow_large`` (counted before any point is built)."""
    count = math.prod(len(v) for _, v in axes)
    if count > MAX_SWEEP_POINTS and not allow_large:
        sizes = " × ".join(str(len(v)) for _, v in axes)
        raise _error(source, lines, "axes", f"the axes span {sizes} = {count} design points, "
                     f"over the limit of {MAX_SWEEP_POINTS} (each is a tuning run; "
                     "rvmsim sweep --allow-large lifts the limit)")
    return count


def _check_tuning(f: _SweepFile, source: str, lines: Mapping[KeyPath, int]) -> None:
    """The strategy is known and ``tune.config`` is a valid tuning config."""

    if f.tune.strategy not in STRATEGIES:
        raise _error(source, lines, "tune.strategy",
                     f"{f.tune.strategy!r} is not one of {', '.join(STRATEGIES)}")
    try:
        TuningConfig.model_validate(f.tune.config)
    except ValidationError as err:
        sub = {k[2:]: n for k, n in lines.items() if k[:2] == ("tune", "config")}
        e = input_error_from_validation(err, source, sub, SweepFileError)
        raise SweepFileError(source, f"tune.config.{e.key}", e.message, e.line) from None


def _read_criteria(f: _SweepFile, folder: Path) -> tuple[str | None, str]:
    """(text, file name) of the sweep's criteria file, checked; (None, "") for the
    defaults."""
    if f.tune.criteria is None:
        return None, ""
    bundled = bundled_criteria_text(f.tune.criteria)  # a bundled set's name (fmvss111-full)
    if bundled is not None and not (folder / f.tune.criteria).exists():
        return bundled, f.tune.criteria
    cpath = Path(f.tune.criteria)
    cpath = cpath if cpath.is_absolute() else (folder / cpath).resolve()
    text = read_text(cpath, CriteriaError)
    criteria_from_text(text, str(cpath))  # its errors now, not in every worker
    return text, str(cpath)


def load_sweep(path: str | Path, *, allow_large: bool = False) -> SweepSpec:
    """Read and check a sweep file, and every design point's scene.

    Parameters
    ----------
    allow_large : bool
        Accept more than :data:`MAX_SWEEP_POINTS` design points (``--allow-large``).

    Raises
    ------
    SweepFileError
        One line naming the sweep file, the key and its line; the base scene's and the
        criteria file's own errors name those files.
    """
    path = Path(path)
    text = read_text(path, SweepFileError)
    data = parse_yaml_mapping(text, str(path), SweepFileError, "a sweep file")
    lines = key_lines(text)
    try:
        f = _SweepFile.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, str(path), lines, SweepFileError) from None
    base = Path(f.base_scene)
    base = base if base.is_absolute() else (path.parent / base).resolve()
    if not base.is_file():
        raise _error(str(path), lines, "base_scene", f"scene file not found: {base}")
    _, base_doc = read_scene_document(base)
    axes = tuple((name, expand_axis(name, v, str(path), lines)) for name, v in f.axes.items())
    _point_count(axes, allow_large, str(path), lines)
    _check_tuning(f, str(path), lines)
    markets = sweep_markets(f.tune.markets, f.tune.criteria is not None, str(path), lines,
                            path.parent)
    criteria_doc, criteria_source = _read_criteria(f, path.parent)
    names = [a for a, _ in axes]
    if f.map is not None and not set(f.map) <= set(names):
        raise _error(str(path), lines, "map",
                     f"{list(f.map)} must name two of the axes {names}")
    spec = SweepSpec(name=f.name, source=str(path), base_scene=base, base_doc=base_doc,
                     axes=axes, strategy=f.tune.strategy, budget=f.tune.budget,
                     seed=f.tune.seed, config=f.tune.config, criteria_doc=criteria_doc,
                     map_axes=f.map, sensitivity=f.sensitivity,
                     criteria_source=criteria_source or "sweep criteria",
                     recheck=RecheckSettings(f.tune.recheck.rounds,
                                             float(f.tune.recheck.budget_factor),
                                             f.tune.recheck.neighbours),
                     robustness=YieldSettings(f.robustness.samples, f.robustness.seed),
                     markets=markets, lines=lines)
    # Every point's scene must load: check them all now, not in a worker an hour later.
    has_variation = False
    for point in design_points(spec):
        doc, _ = point_scene_doc(spec, point.values)
        has_variation = has_variation or doc.get("variation") is not None
    return replace(spec, has_variation=has_variation)


# ---------------------------------------------------------------------------- points
@dataclass(frozen=True)
class DesignPoint:
    """One combination of axis values; ``key`` identifies it across runs (its values)."""

    index: int
    values: tuple[tuple[str, Any], ...]

    @property
    def key(self) -> str:
        return json.dumps([[n, v] for n, v in self.values], separators=(",", ":"))

    @property
    def task_key(self) -> str:
        """A short name for the point's task (executors and Dask keys)."""
        return hashlib.sha256(self.key.encode()).hexdigest()[:16]

    @property
    def label(self) -> str:
        """``name=value, …`` for messages."""
        return _label(self.values)


def design_points(spec: SweepSpec) -> list[DesignPoint]:
    """Every combination, the first axis varying slowest."""
    names = [n for n, _ in spec.axes]
    return [DesignPoint(i, tuple(zip(names, combo)))
            for i, combo in enumerate(itertools.product(*(v for _, v in spec.axes)))]


def _label(values: tuple[tuple[str, object], ...]) -> str:
    return ", ".join(f"{n}={v}" for n, v in values)


def _set_path(spec: SweepSpec, doc: dict[str, Any], path: str, value: object) -> None:
    """Set the scene key at dotted ``path`` (list indices as numbers) to ``value``."""
    key, at = f"axes.{path}", ("axes", path)
    keys: list[str | int] = [int(k) if k.isdigit() else k for k in path.split(".")]
    node: Any = doc  # a mapping, list or value of the scene's YAML document
    for k in keys[:-1]:
        try:
            node = node[k]
        except (KeyError, IndexError, TypeError):
            raise spec.error(key, f"the base scene has no key {path}", at) from None
    last = keys[-1]
    if isinstance(node, list):
        if not isinstance(last, int) or last >= len(node):
            raise spec.error(key, "index out of range", at)
        node[last] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        raise spec.error(key, f"cannot set a key inside a {type(node).__name__}", at)


def _set_intrinsics_fx(base_scene: Scene, doc: dict[str, Any], fx: float) -> None:
    """Intrinsics with focal length ``fx`` px, the base scene's fy/fx, centre and skew."""
    w, h = base_scene.camera.image_size
    base_fx, base_fy, cx, cy, skew = base_scene.camera.intrinsics.resolve(w, h)
    doc["camera"]["intrinsics"] = {"fx": fx, "fy": fx * base_fy / base_fx,
                                   "cx": cx, "cy": cy, "skew": skew}


def _apply_axis(spec: SweepSpec, doc: dict[str, Any], config: dict[str, Any], name: str,
                value: Any, base_scene: Scene | None) -> Scene | None:
    """Write one axis value into the scene document or the tuning config; returns the base
    scene when it had to be loaded (for ``focal_length_px``)."""
    mount = doc.setdefault("camera", {}).setdefault("mount", {})
    if name in POSITION_AXES:
        pos = list(mount.get("position", [0.0, 0.0, 0.0]))
        i, sign = POSITION_AXES[name]
        pos[i] = sign * float(value)
        mount["position"] = pos
    elif name in ("pitch_deg", "yaw_deg", "roll_deg"):
        mount[name] = float(value)
    elif name == "lens_fov_deg":
        doc["camera"].setdefault("lens", {})["fov_deg"] = float(value)
    elif name == "horizontal_fov_deg":
        doc["camera"]["intrinsics"] = {"horizontal_fov_deg": float(value)}
    elif name == "focal_length_px":
        if base_scene is None:
            base_scene = scene_from_dict(spec.base_doc, base_dir=spec.base_scene.parent,
                                         source=str(spec.base_scene))
        _set_intrinsics_fx(base_scene, doc, float(value))
    elif name == "output_size":
        if not (isinstance(value, list) and len(value) == 2):
            raise spec.error("axes.output_size", f"values are [W, H], got {value!r}",
                             ("axes", name))
        config.setdefault("output", {})["size"] = list(value)
    elif "." in name:
        _set_path(spec, doc, name, value)
    else:
        raise spec.error(f"axes.{name}", f"unknown axis (named axes: {', '.join(AXES)}; or "
                                         "a scene key path like vehicle.bumper.top)",
                         ("axes", name))
    return base_scene


def point_scene_doc(spec: SweepSpec, values: tuple[tuple[str, Any], ...]
                    ) -> tuple[dict[str, Any], dict[str, Any]]:
    """(scene document, tuning config document) of one design point.  Mesh paths become
    absolute, so the document loads from anywhere.

    Raises
    ------
    SweepFileError
        An axis that cannot be applied, or a point whose scene is invalid (the message
        names the point and the scene key).
    """
    doc = copy.deepcopy(spec.base_doc)
    config = copy.deepcopy(spec.config)
    absolute_mesh_paths(doc, spec.base_scene.parent)
    base_scene = None
    for name, value in values:
        base_scene = _apply_axis(spec, doc, config, name, value, base_scene)
    label = _label(values)
    try:
        scene_from_dict(doc, base_dir=spec.base_scene.parent, source=f"{spec.source} [{label}]")
    except InputFileError as err:
        where = f"{err.key}: " if err.key else ""
        raise spec.error("axes", f"design point {label}: {where}{err.message}") from None
    except RvmsimError as err:
        raise spec.error("axes", f"design point {label}: {err}") from None
    return doc, config
