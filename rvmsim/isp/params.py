"""The ISP's parameters: the paper's 14 (Table 2) with their ranges, the output image, and
params files (YAML or JSON).

Units: degrees for angles, px for RAD and the H/V shifts (input image px), output half-widths
for the advanced shifts; zoom and the advanced scales are ratios.  The geometry each
parameter controls is :mod:`rvmsim.isp.map` (and ``docs/isp-model.md``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .._io import (KeyPath, image_size_problem, key_lines, read_text, safe_load_limited,
                   yaml_problem)
from ..errors import ParamsFileError

__all__ = [
    "params_judged_at",
    "ParamSpec",
    "PARAM_SPECS",
    "TUNED_BY_DEFAULT",
    "IspParams",
    "OutputSpec",
    "params_to_dict",
    "load_params",
]


_NUMBER = (int, float, np.floating)


@dataclass(frozen=True)
class ParamSpec:
    """One ISP parameter: its name here, the paper's name and symbol, default, range, unit."""

    name: str
    paper_name: str
    symbol: str
    default: float
    low: float
    high: float
    unit: str
    note: str = ""

    def problem(self, value: object) -> str | None:
        """Why ``value`` cannot be this parameter's value (one line, without the name), or
        None when it can: a finite number (int, float or numpy float) in [low, high]."""
        if isinstance(value, bool) or not isinstance(value, _NUMBER):
            return f"must be a number, got {value!r}"
        try:
            number = float(value)
        except OverflowError:  # an integer of hundreds of digits
            return f"a {len(str(abs(int(value))))}-digit number is outside [{self.low:g}, " \
                   f"{self.high:g}] {self.unit}".rstrip()
        if not math.isfinite(number) or not self.low <= number <= self.high:
            return f"{number:g} is outside [{self.low:g}, {self.high:g}] {self.unit}".rstrip()
        return None


#: The 14 parameters of the paper's Table 2.  Where the paper gives no range (FOV, RAD,
#: H/V shift) the range is ours, wide enough for any lens this tool models.
PARAM_SPECS: tuple[ParamSpec, ...] = (
    ParamSpec("fov", "FOV", "FOV", 180.0, 30.0, 240.0, "deg",
              "field of view the ISP assumes for its image circle (range ours)"),
    ParamSpec("rad", "RAD", "RAD", 640.0, 50.0, 2000.0, "px",
              "radius of the ISP's image circle in the input image (range ours)"),
    ParamSpec("h_shift", "H shift", "x_is", 0.0, -500.0, 500.0, "px",
              "image-circle centre right of the input image centre (range ours)"),
    ParamSpec("v_shift", "V shift", "y_is", 0.0, -500.0, 500.0, "px",
              "image-circle centre below the input image centre (range ours)"),
    ParamSpec("h_pan", "H Pan", "θ_cv", 0.0, 0.0, 180.0, "deg",
              "polar angle between the V camera axis and the A camera axis"),
    ParamSpec("v_pan", "V Pan", "φ_cv", 0.0, -180.0, 180.0, "deg",
              "azimuth toward which the V axis turns (0 image right, 90 image down)"),
    ParamSpec("zoom", "Zoom", "r_cv", 1.0, 0.01, 10.0, "",
              "distance of the virtual image plane (output half-width = 1)"),
    ParamSpec("tilt", "Tilt", "α_sz", 0.0, -180.0, 180.0, "deg",
              "roll of the V camera about its axis"),
    ParamSpec("adv_h_shift", "Advanced H shift", "x_os", 0.0, -1.0, 1.0, "",
              "horizontal move of the view window, in output half-widths"),
    ParamSpec("adv_v_shift", "Advanced V shift", "y_os", 0.0, -1.0, 1.0, "",
              "vertical move of the view window, in output half-widths"),
    ParamSpec("adv_h_scale", "Advanced H scale", "s_ox", 1.0, 0.5, 2.0, "",
              "horizontal magnification (> 1 stretches the image horizontally)"),
    ParamSpec("adv_v_scale", "Advanced V scale", "s_oy", 1.0, 0.5, 2.0, "",
              "vertical magnification (> 1 stretches the image vertically)"),
    ParamSpec("theta", "Theta", "θ_st", 0.0, 0.0, 180.0, "deg",
              "tilt of the virtual image plane"),
    ParamSpec("phi", "Phi", "φ_st", 0.0, -180.0, 180.0, "deg",
              "azimuth of the image-plane tilt (0: about the vertical axis)"),
)
_SPEC = {s.name: s for s in PARAM_SPECS}

#: The paper fixes the five angle parameters to 0 and tunes the other nine.
TUNED_BY_DEFAULT: tuple[str, ...] = (
    "fov", "rad", "h_shift", "v_shift", "zoom",
    "adv_h_shift", "adv_v_shift", "adv_h_scale", "adv_v_scale",
)


@dataclass(frozen=True)
class IspParams:
    """The 14 ISP parameters of the paper's Table 2 (ranges in :data:`PARAM_SPECS`).

    Attributes
    ----------
    fov : float
        FOV, degrees: field of view of the ISP's assumed equidistance image circle.
    rad : float
        RAD, px: radius of that image circle in the input (fisheye) image.
    h_shift, v_shift : float
        H/V shift (x_is, y_is), px: image-circle centre relative to the input image centre.
    h_pan, v_pan : float
        H/V pan (θ_cv, φ_cv), degrees: polar angle and azimuth of the V camera axis.
    zoom : float
        Zoom (r_cv): distance of the virtual image plane; larger enlarges.
    tilt : float
        Tilt (α_sz), degrees: roll of the V camera.
    adv_h_shift, adv_v_shift : float
        Advanced H/V shift (x_os, y_os), in [-1, 1] output half-widths.
    adv_h_scale, adv_v_scale : float
        Advanced H/V scale (s_ox, s_oy), in [0.5, 2]; > 1 enlarges along that axis.
    theta, phi : float
        Theta/Phi (θ_st, φ_st), degrees: tilt of the virtual image plane and its azimuth.
    """

    fov: float = 180.0
    rad: float = 640.0
    h_shift: float = 0.0
    v_shift: float = 0.0
    h_pan: float = 0.0
    v_pan: float = 0.0
    zoom: float = 1.0
    tilt: float = 0.0
    adv_h_shift: float = 0.0
    adv_v_shift: float = 0.0
    adv_h_scale: float = 1.0
    adv_v_scale: float = 1.0
    theta: float = 0.0
    phi: float = 0.0

    def __post_init__(self) -> None:
        for spec in PARAM_SPECS:
            value = getattr(self, spec.name)
            if type(value) is float and spec.low <= value <= spec.high:
                continue  # the common case, checked fast (NaN and infinities fail the range)
            problem = spec.problem(value)
            if problem is not None:
                raise ValueError(f"{spec.name}: {problem}")
            object.__setattr__(self, spec.name, float(value))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(s.name for s in PARAM_SPECS)

    def replace(self, **changes: float) -> IspParams:
        """A copy with some parameters changed (validated)."""
        return dataclasses.replace(self, **changes)

    def for_input_scale(self, factor: float) -> IspParams:
        """The same view on a fisheye image resampled by ``factor`` (e.g. a 0.25 preview
        render): RAD and the H/V shifts are in input px, so they scale with it."""
        return self.replace(rad=self.rad * factor, h_shift=self.h_shift * factor,
                            v_shift=self.v_shift * factor)


@dataclass(frozen=True)
class OutputSpec:
    """The RVM image: size in px and whether it is mirrored (RVM displays usually are)."""

    width: int = 1280
    height: int = 720
    mirror: bool = True

    def __post_init__(self) -> None:
        if not (16 <= self.width <= 8192 and 16 <= self.height <= 8192):
            raise ValueError(f"output size must be 16..8192 px, got {self.width}x{self.height}")


# ---------------------------------------------------------------------------- files
def params_to_dict(params: IspParams, output: OutputSpec | None = None, *,
                   judged_at: OutputSpec | None = None) -> dict[str, Any]:
    """Plain dict for a params file (the 14 parameters, then ``output``), to be dumped as
    YAML or JSON.  ``judged_at``: the RVM image of record the setting's ECs were judged at
    (written as ``output.judged_at: [W, H]``; :mod:`rvmsim.criteria.record`)."""
    d: dict[str, Any] = {n: getattr(params, n) for n in IspParams.names()}
    if output is not None:
        d["output"] = {"size": [output.width, output.height], "mirror": output.mirror}
        if judged_at is not None:
            d["output"]["judged_at"] = [judged_at.width, judged_at.height]
    return d


def _parse(text: str, path: Path) -> Any:
    """The document of a params file: JSON for ``.json``, else YAML."""
    try:
        return json.loads(text) if path.suffix.lower() == ".json" else safe_load_limited(text)
    except json.JSONDecodeError as err:
        raise ParamsFileError(str(path), "", f"malformed params file: {err}", err.lineno) from None
    except RecursionError:  # JSON nested thousands of levels deep
        raise ParamsFileError(str(path), "", "malformed params file: nested too deeply") from None
    except yaml.YAMLError as err:
        message, line = yaml_problem(err)
        message = message.replace("malformed YAML", "malformed params file", 1)
        raise ParamsFileError(str(path), "", message, line) from None


def _output_spec(out_data: object, path: Path, lines: Mapping[KeyPath, int]) -> OutputSpec:
    """The ``output`` section of a params file as an :class:`OutputSpec`."""
    def error(key: str, message: str) -> ParamsFileError:
        loc = tuple(key.split("."))
        return ParamsFileError(str(path), key, message, lines.get(loc, lines.get(("output",))))

    output = OutputSpec()
    if not isinstance(out_data, dict) or set(out_data) - {"size", "mirror", "judged_at"}:
        raise error("output", "expected {size: [W, H], mirror: true|false, judged_at: [W, H]}")
    judged = out_data.get("judged_at")
    if judged is not None and (
            not isinstance(judged, list) or len(judged) != 2
            or not all(isinstance(x, int) and not isinstance(x, bool) and 16 <= x <= 8192
                       for x in judged)):
        raise error("output.judged_at", "expected [width, height] in px (16..8192), the RVM "
                    "image of record the ECs were judged at")
    size = out_data.get("size", [output.width, output.height])
    mirror = out_data.get("mirror", output.mirror)
    if (not isinstance(size, list) or len(size) != 2
            or not all(isinstance(x, int) and not isinstance(x, bool) for x in size)):
        raise error("output.size", "expected [width, height] in px")
    if not isinstance(mirror, bool):
        raise error("output.mirror", "expected true or false")
    problem = image_size_problem(size[0], size[1], min_side=16)
    if problem is not None:
        raise error("output.size", problem)
    try:
        return OutputSpec(size[0], size[1], mirror)
    except ValueError as err:
        raise error("output.size", str(err)) from None


def params_judged_at(path: str | Path) -> tuple[int, int] | None:
    """The RVM image of record a params file says its ECs were judged at
    (``output.judged_at: [W, H]``, px), or None where it says none.  Read after
    :func:`load_params` has accepted the file."""
    data = _parse(read_text(Path(path), ParamsFileError, what="params file"), Path(path))
    out = data.get("output") if isinstance(data, dict) else None
    judged = out.get("judged_at") if isinstance(out, dict) else None
    return (int(judged[0]), int(judged[1])) if isinstance(judged, list) else None


def load_params(path: str | Path, *, complete: bool = False) -> tuple[IspParams, OutputSpec]:
    """Read a params file (YAML or JSON): any of the 14 parameter names (missing ones take
    the paper's defaults) and an optional ``output: {size: [W, H], mirror: bool}`` (its
    ``judged_at: [W, H]``, the RVM image of record the ECs were judged at, is checked and
    otherwise informational: every verdict is at the reader's image of record).

    Parameters
    ----------
    path : path
    complete : bool
        Every one of the 14 parameters must be given (none taken from the defaults): a
        setting that is written into a car (``rvmsim eol``'s platform setting).

    Raises
    ------
    ParamsFileError
        One line naming the file (and the line where known) and the key, for unreadable
        or empty files, malformed YAML/JSON, unknown keys, non-numbers, values out of
        range and, with ``complete``, a parameter not given.
    """
    path = Path(path)
    text = read_text(path, ParamsFileError, what="params file")
    data = _parse(text, path)
    if data is None:
        raise ParamsFileError(str(path), "", "empty: no ISP parameters (the paper's defaults "
                              "are params/paper_defaults.yaml)")
    if not isinstance(data, dict):
        raise ParamsFileError(str(path), "", "a params file must be a mapping (name: value)")
    lines = key_lines(text)
    data = dict(data)
    out_data = data.pop("output", None)
    unknown = sorted(set(data) - set(IspParams.names()), key=str)
    if unknown:
        key = str(unknown[0])
        raise ParamsFileError(str(path), key, "unknown ISP parameter "
                              f"(known: {', '.join(IspParams.names())})", lines.get((key,)))
    for key, value in data.items():
        problem = _SPEC[key].problem(value)
        if problem is not None:
            raise ParamsFileError(str(path), key, problem, lines.get((key,)))
    missing = [k for k in IspParams.names() if k not in data]
    if complete and missing:
        raise ParamsFileError(str(path), missing[0], "not given: a setting written into a car "
                              "names all 14 parameters (none is taken from the defaults; "
                              f"missing: {', '.join(missing)})")
    params = IspParams(**{k: float(v) for k, v in data.items()})
    output = OutputSpec() if out_data is None else _output_spec(out_data, path, lines)
    return params, output
