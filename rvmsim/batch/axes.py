"""A sweep file's axes: the named axes, and an axis's values expanded from a list or a range
(:func:`expand_axis`), each value checked (:func:`axis_value_problem`).

Split from :mod:`rvmsim.batch.spec` (the sweep file), which re-exports :data:`AXES`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .._io import KeyPath, image_size_problem, input_error_from_validation, line_of
from ..errors import SweepFileError

__all__ = ["AXES", "POSITION_AXES", "MAX_AXIS_VALUES", "sweep_error", "expand_axis",
           "axis_value_problem", "short_repr"]

#: Most values of one axis (a list or a range).
MAX_AXIS_VALUES = 1000

#: Named axes: name → where a value is written.  Heights are positive up; the camera
#: position's y is negative up.
AXES: dict[str, str] = {
    "camera_height_m": "camera.mount.position.1 = -value",
    "lateral_offset_m": "camera.mount.position.0 = value",
    "bumper_overhang_m": "camera.mount.position.2 = -value (camera this far ahead of the "
                         "bumper's rearmost point)",
    "pitch_deg": "camera.mount.pitch_deg",
    "yaw_deg": "camera.mount.yaw_deg",
    "roll_deg": "camera.mount.roll_deg",
    "focal_length_px": "camera.intrinsics fx = value, fy keeping the base fy/fx, same centre",
    "horizontal_fov_deg": "camera.intrinsics = {horizontal_fov_deg: value}",
    "lens_fov_deg": "camera.lens.fov_deg",
    "output_size": "the tuning config's output.size ([W, H]): the RVM image the ECs see",
}

#: Position axes: name → (index in camera.mount.position, sign of the value there).
POSITION_AXES = {"camera_height_m": (1, -1), "lateral_offset_m": (0, 1),
                  "bumper_overhang_m": (2, -1)}


class _Range(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    start: float
    stop: float
    num: int | None = Field(default=None, ge=1, le=MAX_AXIS_VALUES)
    step: float | None = Field(default=None, gt=0)


def sweep_error(source: str, lines: Mapping[KeyPath, int], key: str, message: str,
           at: KeyPath | None = None) -> SweepFileError:
    """A :class:`SweepFileError` naming ``key``, on the line of the longest known prefix of
    the key path ``at`` (default: ``key`` split at its dots)."""
    parts = at if at is not None else (tuple(key.split(".")) if key else ())
    return SweepFileError(source, key, message, line_of(lines, parts))


def expand_axis(name: str, v: Any, source: str, lines: Mapping[KeyPath, int]
            ) -> tuple[Any, ...]:
    """An axis's values (``v`` from the YAML): a list as given, a range expanded (stop included)."""
    key, at = f"axes.{name}", ("axes", name)
    vals: np.ndarray
    if isinstance(v, dict):
        try:
            v = _Range.model_validate(v)
        except ValidationError as err:
            sub = {k[2:]: n for k, n in lines.items() if k[:2] == at}
            e = input_error_from_validation(err, source, sub, SweepFileError)
            raise SweepFileError(source, f"{key}.{e.key}", e.message,
                                 e.line or line_of(lines, at)) from None
    elif not isinstance(v, list):
        raise sweep_error(source, lines, key, "an axis is a list of values or a range "
                     "{start, stop, num or step}", at)
    if isinstance(v, _Range):
        if v.num is not None and v.step is None:
            vals = np.linspace(v.start, v.stop, v.num)
        elif v.step is not None and v.num is None:
            count = (v.stop - v.start) / v.step + 1e-9
            if not 0 <= count < MAX_AXIS_VALUES:  # also a count too large to be an int
                raise sweep_error(source, lines, key, f"the range gives {count + 1:.6g} values "
                             f"(1..{MAX_AXIS_VALUES})", at)
            n = int(math.floor(count)) + 1
            vals = v.start + v.step * np.arange(n)
        else:
            raise sweep_error(source, lines, key, "give a range either num or step", at)
        return tuple(round(float(x), 10) for x in vals)
    if not v:
        raise sweep_error(source, lines, key, "no values", at)
    if len(v) > MAX_AXIS_VALUES:
        raise sweep_error(source, lines, key, f"{len(v)} values (at most {MAX_AXIS_VALUES})", at)
    for i, value in enumerate(v):
        problem = axis_value_problem(name, value)
        if problem is not None:
            raise sweep_error(source, lines, key, f"value {i + 1} ({short_repr(value)}): {problem}",
                         at + (i,))
    return tuple(v)


def axis_value_problem(axis: str, value: object) -> str | None:
    """Why ``value`` cannot be a value of the named ``axis`` (one line), or None; values of
    scene-key axes are checked with each point's scene."""
    if axis == "output_size":
        if (not isinstance(value, list) or len(value) != 2
                or not all(isinstance(x, int) and not isinstance(x, bool) for x in value)):
            return "values are [W, H] in px"
        if not all(16 <= x <= 8192 for x in value):
            return "output sizes are 16..8192 px"
        return image_size_problem(value[0], value[1], min_side=16)
    if axis in AXES:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return "must be a number"
        if abs(value) > 1e7 or not math.isfinite(value):  # abs first: a 400-digit int
            return "must be a finite number within ±1e7"
    return None


def short_repr(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:30] + "…"
