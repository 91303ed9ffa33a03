"""Criteria files: YAML → :class:`rvmsim.criteria.Criteria`.

A criteria file is data (read with YAML's safe loader); the only code it brings in is the
plugins it names explicitly under ``plugins:``.  Format (every key optional)::

    name: OEM X
    upper_region_fraction: 0.5      # measurement options
    edge_columns: 4
    plugins: [acme_rvm.criteria, ./board_centred.py]   # modules, or files next to this one
    ecs: [1-1, 1-2, acme-board-x]   # the selected ECs, in evaluation order
    display: {eye_distance_mm: 650} # the driver's display (EC 1-6; a scene's own wins)
    criteria:                       # per EC: what changes from its defaults
      2-1: {range: [5, 9], tolerance: 1.0}
      4-1: {enabled: false}
      6-1: {parameters: {max_magnification: 2.5}}   # an EC's named parameters

Without ``ecs``, a file selects the ECs of the criteria it extends (the paper's eleven),
then every EC of its plugins, in the order listed.  Bundled criteria sets are selected by
name wherever a criteria file is (:data:`BUNDLED_CRITERIA`: ``fmvss111-full``, ``unr158``,
``jp``).  See
docs/criteria.md.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Annotated

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, model_validator

from .._io import (FilePathText, KeyPath, input_error_from_validation, key_lines, line_of, parse_yaml_mapping,
                   read_text)
from ..errors import CriteriaError
from ..scene import Display
from .registry import EcDefinition, builtin_ecs, load_plugin, resolve_plugin
from .scoring import Criteria
from .sigmoid import Criterion, Sigmoid

__all__ = ["load_criteria", "default_criteria", "criteria_from_text", "BUNDLED_CRITERIA",
           "bundled_criteria_text", "criteria_reference"]

#: Criteria sets shipped with rvmsim, selected by name (``--criteria fmvss111-full``, a sweep
#: file's ``criteria:``): name → the regulation package holding it as ``criteria.yaml``
#: (:mod:`rvmsim.regulations`, read as data).
BUNDLED_CRITERIA: dict[str, str] = {"fmvss111-full": "rvmsim.regulations.fmvss111",
                                    "unr158": "rvmsim.regulations.unr158",
                                    "jp": "rvmsim.regulations.jp",
                                    "guidelines": "rvmsim.guidelines"}


def _not_nan(value: float) -> float:
    if math.isnan(value):
        raise ValueError("must be a number, not NaN")
    return value


#: A float that may be ±infinity (an open threshold) but not NaN.
_Number = Annotated[float, AfterValidator(_not_nan)]


class _SigmoidModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    c1: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 1.0
    c2: _Number = -math.inf
    c3: Annotated[float, Field(ge=0, allow_inf_nan=False)] = 1.0
    c4: _Number = math.inf


class _CriterionModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    enabled: bool = True
    range: tuple[_Number | None, _Number | None] | None = None
    sigmoid: _SigmoidModel | None = None
    tolerance: Annotated[float, Field(gt=0, allow_inf_nan=False)] | None = None
    parameters: dict[str, Annotated[float, Field(allow_inf_nan=False)]] = {}

    @model_validator(mode="after")
    def _check(self) -> _CriterionModel:
        if self.sigmoid is not None and self.tolerance is not None:
            raise ValueError("give either sigmoid coefficients or a tolerance, not both")
        if self.tolerance is not None and self.range is None:
            raise ValueError("a tolerance needs a range to derive the sigmoid from")
        if self.range is not None:
            lo, hi = self.range
            if lo is not None and hi is not None and lo > hi:
                raise ValueError("range must be [low, high] with low <= high")
        if self.sigmoid is not None and self.sigmoid.c2 > self.sigmoid.c4:
            raise ValueError("sigmoid thresholds need c2 <= c4")
        return self


class _CriteriaModel(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = "criteria"
    upper_region_fraction: Annotated[float, Field(gt=0, le=1)] = 0.5
    edge_columns: Annotated[int, Field(ge=1, le=64)] = 4
    plugins: list[FilePathText] = []
    ecs: list[str] | None = None
    display: Display | None = None
    criteria: dict[str, _CriterionModel] = {}


class _File:
    """One criteria file being read: its name, key lines and folder, for errors and paths."""

    def __init__(self, text: str, source: str, base_dir: Path):
        self.source = source
        self.lines = key_lines(text)
        self.base_dir = base_dir

    def error(self, path: KeyPath, message: str) -> CriteriaError:
        return CriteriaError(self.source, ".".join(str(p) for p in path), message,
                             line_of(self.lines, path))


def _available(model: _CriteriaModel, base: Criteria | None, f: _File) -> dict[str, EcDefinition]:
    """Every EC the file may select: the built-ins, the base's, and its plugins' ECs."""
    available = {ec.id: ec for ec in builtin_ecs()}
    available.update({ec.id: ec for ec in (base.ecs if base is not None else ())})
    for i, entry in enumerate(model.plugins):
        try:
            ecs = load_plugin(resolve_plugin(entry, f.base_dir))
        except CriteriaError as err:
            where = f"{err.key}: " if err.key else ""
            raise f.error(("plugins", i), f"plugin {entry!r}: {where}{err.message}") from None
        for ec in ecs:
            seen = available.setdefault(ec.id, ec)
            if seen is not ec:
                raise f.error(("plugins", i), f"plugin {entry!r} defines EC {ec.id!r}, which "
                              f"{seen.plugin or 'another plugin'} defines already")
    return available


def _selection(model: _CriteriaModel, base: Criteria | None, available: dict[str, EcDefinition],
               f: _File) -> list[str]:
    """The selected EC ids in evaluation order (see the module docstring)."""
    def unknown(ec: str) -> str:
        return f"unknown EC {ec!r} (known: {', '.join(available)})"

    if model.ecs is not None:
        for i, ec in enumerate(model.ecs):
            if ec not in available:
                raise f.error(("ecs", i), unknown(ec))
            if ec in model.ecs[:i]:
                raise f.error(("ecs", i), f"EC {ec!r} is selected twice")
        for ec in model.criteria:
            if ec not in model.ecs:
                raise f.error(("criteria", ec), f"EC {ec!r} is not selected (add it to ecs)")
        selected = list(model.ecs)
    else:
        for ec in model.criteria:
            if ec not in available:
                raise f.error(("criteria", ec), unknown(ec))
        builtin = {ec.id for ec in builtin_ecs()}
        plugged = [ec.id for ec in available.values() if ec.plugin and ec.id not in builtin]
        selected = list(dict.fromkeys([*(base.ids if base is not None else ()), *plugged,
                                       *model.criteria]))
    if not selected:
        raise f.error(("ecs",), "no EC selected")
    return selected


def _criterion(ec: EcDefinition, prev: Criterion, m: _CriterionModel | None) -> Criterion:
    """``prev`` with the changes a file makes to one EC."""
    if m is None:
        return prev
    low, high = (prev.low, prev.high) if m.range is None else m.range
    if ec.binary:
        sig = None
    elif m.sigmoid is not None:
        sig = Sigmoid(m.sigmoid.c1, m.sigmoid.c2, m.sigmoid.c3, m.sigmoid.c4)
    elif m.tolerance is not None:
        sig = Sigmoid.from_range(low, high, m.tolerance)
    else:
        sig = prev.sigmoid
    return Criterion(ec.id, low, high, sig, m.enabled)


def _parameters(ec: EcDefinition, base: Criteria | None, m: _CriterionModel | None,
                f: _File) -> dict[str, float]:
    """The changes a file (and the criteria it extends) make to an EC's parameters."""
    out = dict(base.parameters.get(ec.id, {})) if base is not None else {}
    known = dict(ec.parameters)
    for name, value in (m.parameters if m is not None else {}).items():
        if name not in known:
            raise f.error(("criteria", ec.id, "parameters", name), f"EC {ec.id!r} has no "
                          f"parameter {name!r} (known: {', '.join(known) or 'none'})")
        out[name] = float(value)
    return out


def _load(text: str, source: str, base: Criteria | None, base_dir: Path) -> Criteria:
    data = parse_yaml_mapping(text, source, CriteriaError, "a criteria file", empty_ok=True)
    if isinstance(data.get("criteria"), dict):  # YAML may read 1-1 … as strings already
        data["criteria"] = {str(k): v for k, v in data["criteria"].items()}
    if isinstance(data.get("ecs"), list):  # an id such as 5 reads as a number
        data["ecs"] = [str(v) if isinstance(v, int) else v for v in data["ecs"]]
    f = _File(text, source, base_dir)
    try:
        model = _CriteriaModel.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, source, f.lines, CriteriaError) from None
    available = _available(model, base, f)
    items: dict[str, Criterion] = {}
    params: dict[str, dict[str, float]] = {}
    for ec_id in _selection(model, base, available, f):
        ec = available[ec_id]
        prev = base.items.get(ec_id) if base is not None else None
        items[ec_id] = _criterion(ec, prev or ec.default_criterion(), model.criteria.get(ec_id))
        params[ec_id] = _parameters(ec, base, model.criteria.get(ec_id), f)
    display = model.display or (base.display if base is not None else None)
    criteria = Criteria(model.name, items, model.upper_region_fraction, model.edge_columns,
                        source, tuple(available[i] for i in items), display,
                        {k: v for k, v in params.items() if v})
    try:
        criteria.groups  # noqa: B018 - two ECs may not give one group name different labels
    except ValueError as err:
        raise f.error(("plugins",), f"the selected ECs disagree: {err}") from None
    return criteria


def default_criteria() -> Criteria:
    """The shipped defaults: the paper's eleven ECs with its thresholds and sigmoid
    coefficients (``rvmsim/criteria/criteria_default.yaml``; the values are the ECs' defaults,
    see ``rvmsim/criteria/builtin.py`` for how each was derived from the paper's figures)."""
    text = resources.files("rvmsim.criteria").joinpath("criteria_default.yaml").read_text("utf-8")
    return _load(text, "criteria_default.yaml", None, Path("."))


def load_criteria(path: str | Path | None) -> Criteria:
    """Read a criteria file; ECs it does not mention keep the defaults.

    Plugins named by a path are resolved relative to the file's folder.

    Raises
    ------
    CriteriaError
        One line naming the file, line and key for any problem.
    """
    if path is None:
        return default_criteria()
    text = bundled_criteria_text(path)
    if text is not None:
        return _load(text, str(path), default_criteria(), Path("."))
    path = Path(path)
    if not path.exists() and not path.suffix:  # perhaps a misspelt bundled set's name
        raise CriteriaError(str(path), "", "no such file or bundled criteria set (bundled: "
                            f"{', '.join(BUNDLED_CRITERIA)})")
    return _load(read_text(path, CriteriaError), str(path), default_criteria(), path.parent)


def bundled_criteria_text(name: str | Path) -> str | None:
    """The text of the bundled criteria set ``name`` (:data:`BUNDLED_CRITERIA`), or None when
    ``name`` is no bundled set's name or an existing file of that name is in the way (a
    file always wins)."""
    key = str(name)
    if key not in BUNDLED_CRITERIA or Path(key).exists():
        return None
    return resources.files(BUNDLED_CRITERIA[key]).joinpath("criteria.yaml").read_text("utf-8")


def criteria_reference(value: str | Path) -> str:
    """How a run records its criteria: a bundled set's name as given, a file's absolute path
    (so that ``--resume`` and ``report`` find the same criteria from anywhere)."""
    if bundled_criteria_text(value) is not None:
        return str(value)
    return str(Path(value).resolve())


def criteria_from_text(text: str, source: str = "<criteria>", *,
                       base_dir: str | Path | None = None) -> Criteria:
    """A criteria file's text (as :func:`load_criteria` reads it) → :class:`Criteria`.

    ``source`` names the text in error messages; plugins named by a relative path are
    resolved against ``base_dir`` (default: the folder of ``source``, i.e. the current
    directory unless ``source`` is a path).
    """
    folder = Path(source).parent if base_dir is None else Path(base_dir)
    return _load(text, source, default_criteria(), folder)
