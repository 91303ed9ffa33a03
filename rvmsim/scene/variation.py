"""The schema of production variation: a scene's ``variation`` section, or a variation file.

Per-axis distributions of the camera mount's tolerance (position in mm, angles in degrees)
and discrete load states.  The models validate the YAML (unknown keys are errors); the
frozen dataclasses the rest of rvmsim uses are built from them by :mod:`rvmsim.robust`.

Example (the section of a scene file, or a variation file's whole content)::

    mount:
      x_mm: {uniform: {half_width: 5}}
      yaw_deg: {normal: {sigma: 0.5, truncate: 2}}
      position_levels: 2
    load_states:
      - {name: curb, height_mm: 0, pitch_deg: 0, weight: 0.3}
      - {name: full, height_mm: -50, pitch_deg: 1.0, weight: 0.2}

Conventions
-----------
Mount offsets are in the scene frame (:mod:`rvmsim.camera.mount`: x toward the driver's
side, y toward the ground, z rearward; mm) and add to the mount angles (degrees, same
signs).  A load state's ``height_mm`` is the change of the camera's height above the ground
(a load lowers it: negative); ``pitch_deg`` > 0 is the body pitching rear-down, which turns
the camera's optical axis further down (like a larger mount pitch).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from .compensation import CompensationSpec

__all__ = ["VariationSpec", "MountTolerance", "AxisSpec", "UniformSpec", "NormalSpec",
           "LoadStateSpec", "MOUNT_AXES"]

#: The mount axes, in the order samples hold them.
MOUNT_AXES = ("x_mm", "y_mm", "z_mm", "yaw_deg", "pitch_deg", "roll_deg")
#: Largest tolerance accepted: mm for positions, degrees for angles.
_MAX_MM, _MAX_DEG = 200.0, 20.0


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class UniformSpec(_Model):
    """Uniform on [−half_width, +half_width]."""

    half_width: Annotated[float, Field(ge=0)]


class NormalSpec(_Model):
    """Normal of standard deviation ``sigma``, truncated at ±``truncate`` σ."""

    sigma: Annotated[float, Field(ge=0)]
    truncate: Annotated[float, Field(gt=0, le=10)] = 3.0


class AxisSpec(_Model):
    """One axis's distribution: exactly one of ``uniform`` and ``normal``."""

    uniform: UniformSpec | None = None
    normal: NormalSpec | None = None

    @model_validator(mode="after")
    def _one(self) -> AxisSpec:
        if (self.uniform is None) == (self.normal is None):
            raise ValueError("give exactly one of uniform: {half_width: …} and "
                             "normal: {sigma: …, truncate: …}")
        return self

    @property
    def bound(self) -> float:
        """Largest absolute offset the distribution gives."""
        if self.uniform is not None:
            return self.uniform.half_width
        assert self.normal is not None
        return self.normal.sigma * self.normal.truncate


class MountTolerance(_Model):
    """Tolerance of the camera mount relative to the body; an axis left out does not vary.

    ``position_levels``: rendered positions per varying position axis (each continuous
    position offset is rendered at the centre of its equal-probability bin; see
    docs/robustness.md for the landmark error this costs)."""

    x_mm: AxisSpec | None = None
    y_mm: AxisSpec | None = None
    z_mm: AxisSpec | None = None
    yaw_deg: AxisSpec | None = None
    pitch_deg: AxisSpec | None = None
    roll_deg: AxisSpec | None = None
    position_levels: Annotated[int, Field(ge=1, le=9)] = 2

    @field_validator(*MOUNT_AXES)
    @classmethod
    def _bound(cls, spec: AxisSpec | None, info: ValidationInfo) -> AxisSpec | None:
        name = str(info.field_name)
        limit = _MAX_MM if name.endswith("_mm") else _MAX_DEG
        if spec is not None and spec.bound > limit:
            raise ValueError(f"reaches ±{spec.bound:g}, more than the ±{limit:g} "
                             f"{'mm' if name.endswith('_mm') else '°'} a tolerance may have")
        return spec


class LoadStateSpec(_Model):
    """A discrete load state: camera height change (mm, negative = lower), body pitch
    (degrees, rear down > 0) and its share of production (weights are normalised)."""

    name: Annotated[str, Field(min_length=1, max_length=40)]
    height_mm: Annotated[float, Field(ge=-300, le=300)] = 0.0
    pitch_deg: Annotated[float, Field(ge=-10, le=10)] = 0.0
    weight: Annotated[float, Field(gt=0, le=1e6)] = 1.0


class VariationSpec(_Model):
    """Production variation: mount tolerances and load states (both optional), the
    end-of-line compensation that meets it (optional; used with ``--compensation``), and
    the least production yield that passes (``min_yield``, 0–1; optional: the default of
    ``rvmsim robustness --min-yield`` and ``rvmsim signoff --min-yield``)."""

    mount: MountTolerance = MountTolerance()
    load_states: Annotated[list[LoadStateSpec], Field(max_length=20)] = []
    compensation: CompensationSpec | None = None
    min_yield: Annotated[float, Field(ge=0, le=1)] | None = None

    @field_validator("load_states")
    @classmethod
    def _names(cls, states: list[LoadStateSpec]) -> list[LoadStateSpec]:
        names = [s.name for s in states]
        if len(set(names)) != len(names):
            raise ValueError(f"load state names must differ, got {names}")
        return states
