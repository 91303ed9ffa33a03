"""The tuning config file (``rvmsim tune --config``): tuned parameters, ranges, strategy
settings; and the strategy it describes (:func:`make_strategy`, through the registry)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated

import numpy as np
from pydantic import (BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator,
                      model_validator)

from .._io import (KeyPath, image_size_problem, input_error_from_validation, key_lines, line_of,
                   parse_yaml_mapping, read_text)
from ..camera import FisheyeCamera
from ..errors import InputFileError, RvmsimError, TuningConfigError
from ..isp import PARAM_SPECS, IspParams, OutputSpec
from .space import ParamRange, SearchSpace, default_space
from .strategies import (
    CmaesSolvedSettings,
    STRATEGIES,
    CmaesSettings,
    GridRandomSettings,
    RandomSettings,
    Strategy,
)
from ..scene import RVM_IMAGE_OF_RECORD_PX

__all__ = ["TuningConfig", "DiverseConfig", "load_tuning_config", "make_strategy"]


_SPEC = {s.name: s for s in PARAM_SPECS}


class _Range(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    init: float | None = None
    range: tuple[float, float] | None = None
    step: Annotated[float, Field(gt=0)] | None = None
    points: Annotated[int, Field(ge=1, le=99)] | None = None

    @model_validator(mode="after")
    def _ordered(self) -> _Range:
        if self.range is not None and self.range[0] > self.range[1]:
            raise ValueError(f"range must be [low, high] with low <= high, got {list(self.range)}")
        return self


class _Output(BaseModel):
    model_config = ConfigDict(extra="forbid")
    #: The size the search measures at; None: the RVM image of record (the display's
    #: ``rvm_image_px``, :mod:`rvmsim.criteria.record`).
    size: tuple[Annotated[int, Field(ge=16, le=8192)], Annotated[int, Field(ge=16, le=8192)]] | None = None
    mirror: bool = True

    @field_validator("size")
    @classmethod
    def _pixels(cls, size: tuple[int, int] | None) -> tuple[int, int] | None:
        if size is None:
            return None
        problem = image_size_problem(*size, min_side=16)
        if problem is not None:
            raise ValueError(problem)
        return size


class DiverseConfig(BaseModel):
    """The ``diverse`` section: how the top-M candidates are chosen (see
    :mod:`rvmsim.runs.diverse` and docs/tuning.md).

    ``m``: the candidates offered (default: ``top_m``); ``min_distance``: the least distance
    between any two of them in normalised parameter space (each tuned parameter divided by
    its search span, so 0.05 is 5 % of one parameter's span); ``score_tolerance``: trials
    that fail but score within this fraction of the best EC score come after the all-pass
    ones (and before any other).
    """

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    m: Annotated[int, Field(ge=1, le=1000)] | None = None
    min_distance: Annotated[float, Field(gt=0, le=1)] = 0.05
    score_tolerance: Annotated[float, Field(ge=0, lt=1)] = 0.02


class TuningConfig(BaseModel):
    """A tuning config file (YAML); every key optional.

    ``tuned``: the parameters to search (default: the paper's nine); ``parameters``: per
    parameter ``init``, ``range`` and coarse ``step`` (default: fitted to the camera, see
    :func:`rvmsim.search.default_space`); ``fixed``: values of untuned parameters;
    ``output``: the RVM image the ECs are measured on during tuning (default: the RVM
    image of record; a smaller size is faster on some paths and is judged at the size of record
    all the same, :mod:`rvmsim.criteria.record`); ``top_m`` and
    ``diverse``: the candidates offered for the final choice (:class:`DiverseConfig`); one
    section per
    registered strategy (``grid_random``, ``cmaes``, ``random``: each strategy's
    ``section`` and ``Settings``, which reject keys the strategy does not use).
    """

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    tuned: list[str] | None = None
    parameters: dict[str, _Range] = {}
    fixed: dict[str, float] = {}
    output: _Output = _Output()
    top_m: Annotated[int, Field(ge=1, le=1000)] = 10
    diverse: DiverseConfig = DiverseConfig()
    #: Candidates evaluated (and stored in one transaction) at a time.
    batch: Annotated[int, Field(ge=1, le=100000)] = 1024
    # The registered strategies' sections (a test checks they match the registry).
    grid_random: GridRandomSettings = GridRandomSettings()
    cmaes: CmaesSettings = CmaesSettings()
    cmaes_solved: CmaesSolvedSettings = CmaesSolvedSettings()
    random: RandomSettings = RandomSettings()
    #: The file it was read from and its key lines, for errors (not keys of the file).
    _source: str = PrivateAttr(default="<tuning config>")
    _lines: Mapping[KeyPath, int] = PrivateAttr(default_factory=dict)

    def error(self, path: KeyPath, message: str) -> TuningConfigError:
        """A :class:`TuningConfigError` at the key path ``path`` of this config's file."""
        return TuningConfigError(self._source, ".".join(str(p) for p in path), message,
                                 line_of(self._lines, path))

    def space(self, camera: FisheyeCamera) -> SearchSpace:
        """The search space on ``camera``: the default one with this config's changes.

        Raises
        ------
        TuningConfigError
            An ``init`` outside the range it ends up with on this camera (a config without
            ``range`` keeps the camera's default range).
        """
        names = tuple(self.tuned) if self.tuned is not None else None
        base_space = default_space(camera) if names is None else default_space(camera, names)
        ranges = []
        for r in base_space.ranges:
            o = self.parameters.get(r.name)
            if o is None:
                ranges.append(r)
                continue
            lo, hi = o.range if o.range is not None else (r.low, r.high)
            if o.init is not None and not lo <= o.init <= hi:
                raise self.error(("parameters", r.name, "init"), f"{o.init:g} is outside the "
                                 f"range [{lo:g}, {hi:g}] it is searched in on this camera")
            init = o.init if o.init is not None else min(max(r.init, lo), hi)
            ranges.append(ParamRange(r.name, init, lo, hi, o.step or r.step, o.points or r.points))
        base = IspParams().replace(**self.fixed) if self.fixed else IspParams()
        return SearchSpace(tuple(ranges), base)

    def check_values(self) -> None:
        """Every parameter's ``range``, ``init`` and ``fixed`` value within the parameter's
        own range (:data:`rvmsim.isp.PARAM_SPECS`), so the run cannot fail on them later.

        Raises
        ------
        TuningConfigError
            Naming the key (``parameters.rad.range``, ``fixed.tilt``) and the limits.
        """
        for name, o in self.parameters.items():
            spec = _SPEC.get(name)
            if spec is None:
                continue
            for k, v in (("range", o.range[0] if o.range else None),
                         ("range", o.range[1] if o.range else None), ("init", o.init)):
                problem = None if v is None else spec.problem(v)
                if problem is not None:
                    raise self.error(("parameters", name, k), problem)
            if o.range is not None and o.init is not None and not o.range[0] <= o.init <= o.range[1]:
                raise self.error(("parameters", name, "init"),
                                 f"{o.init:g} is outside its range {list(o.range)}")
        for name, value in self.fixed.items():
            problem = _SPEC[name].problem(value) if name in _SPEC else None
            if problem is not None:
                raise self.error(("fixed", name), problem)

    @property
    def diverse_m(self) -> int:
        """The candidates offered: ``diverse.m``, else ``top_m``."""
        return self.diverse.m if self.diverse.m is not None else self.top_m

    def output_spec(self) -> OutputSpec:
        """The RVM image the ECs are measured on while tuning (the search size; without
        ``output.size``: the default RVM image of record, :meth:`at_record` sets a scene's)."""

        w, h = self.output.size or RVM_IMAGE_OF_RECORD_PX
        return OutputSpec(w, h, self.output.mirror)

    def at_record(self, size: tuple[int, int]) -> TuningConfig:
        """This config with the search size set to ``size`` (the RVM image of record, W × H
        px) when the file sets none; a run records the result, so resuming measures where it
        started."""
        if self.output.size is not None:
            return self
        out = self.output.model_copy(update={"size": (int(size[0]), int(size[1]))})
        done = self.model_copy(update={"output": out})
        done._source, done._lines = self._source, self._lines
        return done

    def strategy_settings(self, name: str) -> BaseModel:
        """The settings of registered strategy ``name``: its section of this config, or the
        defaults of its ``Settings`` for a strategy without a section (``section = ""``: a
        strategy registered by a user, which a config file cannot set up)."""
        cls = STRATEGIES[name]
        if not cls.section:
            return cls.Settings()
        settings = getattr(self, cls.section, None)
        if not isinstance(settings, cls.Settings):
            raise RvmsimError(f"strategy {name!r}: section {cls.section!r} is not a "
                              f"{cls.Settings.__name__} of the tuning config")
        return settings


def load_tuning_config(path: str | Path | None) -> TuningConfig:
    """Read and validate a tuning config file (None: the defaults).

    Raises
    ------
    TuningConfigError
        One line naming the file and the key: a YAML error, an unknown or out-of-range key
        (also a strategy setting the strategy does not use, such as ``random.sigma0``), or
        a name that is not an ISP parameter.
    """
    if path is None:
        return TuningConfig()
    path = Path(path)
    text = read_text(path, TuningConfigError)
    data = parse_yaml_mapping(text, str(path), TuningConfigError, "a tuning config",
                              empty_ok=True)
    lines = key_lines(text)
    try:
        cfg = TuningConfig.model_validate(data)
    except ValidationError as err:
        bad = input_error_from_validation(err, str(path), lines, TuningConfigError)
        raise _unused_setting(bad) from None
    cfg._source, cfg._lines = str(path), lines
    unknown = set(cfg.tuned or []) | set(cfg.parameters) | set(cfg.fixed)
    unknown -= set(IspParams.names())
    if unknown:
        raise TuningConfigError(str(path), sorted(unknown)[0], "not an ISP parameter")
    cfg.check_values()
    return cfg


def _unused_setting(err: InputFileError) -> InputFileError:
    """An unknown key inside a strategy's section, said as such (``random.sigma0``: the
    random strategy has no step size); any other error as it is."""
    section, _, setting = err.key.partition(".")
    by_section = {cls.section: cls for cls in STRATEGIES.values()}
    cls = by_section.get(section)
    if cls is None or not setting or "." in setting or err.message != "unknown key":
        return err
    return TuningConfigError(err.file, err.key, f"not a setting of the {cls.name} strategy "
                             f"(its settings: {', '.join(cls.Settings.model_fields)})", err.line)


def make_strategy(name: str, space: SearchSpace, cfg: TuningConfig, seed: int,
                  budget: int | None = None, starts: Sequence[np.ndarray] = ()) -> Strategy:
    """The registered strategy ``name`` on ``space``, set up by the config's section.

    Parameters
    ----------
    budget : int, optional
        ``--budget``: evaluations for ``cmaes``/``random``, fine trials per seed (T) for
        ``grid-random``; replaces the config's value.
    starts : sequence of ndarray
        Candidates (vectors of ``space``) to start from, e.g. a neighbouring design point's
        optimum (:attr:`Strategy.starts`); strategies that cannot use them ignore them.
    """
    cls = STRATEGIES.get(name)
    if cls is None:
        raise RvmsimError(f"unknown strategy {name!r} (known: {', '.join(STRATEGIES)})")
    strategy = cls.from_settings(space, cfg.strategy_settings(name), seed=seed, budget=budget,
                                 batch=cfg.batch)
    strategy.set_starts(starts)
    return strategy
