"""The schema of end-of-line (EOL) compensation: a ``compensation`` section of a variation
file (or a scene's ``variation`` section), or a compensation file of the same keys.

Example (every key optional; these are the defaults)::

    compensation:
      params: [h_pan, v_pan, tilt]     # the ISP parameters the EOL step writes per car
      ranges:                          # allowed per-car offsets from the platform setting
        h_pan: [0, 3]                  #   the turn of the view axis, degrees (any direction)
        tilt: [-3, 3]                  #   degrees
      station:
        angle_sigma_deg: 0.1           # the station's measurement error, 1 σ (assumption)
        position_sigma_mm: 1.0         #   (assumption)
        edge_sigma_px: 0.3             # the body edge found on the capture, 1 σ (measured)
        measured_at: null              # the load state on the line (default: the first)
        marginal: fail                 # a car whose margin is inside its uncertainty
      law: ec-solve                    # how the per-car values are chosen
      budget: 24                       # ec-solve: EC evaluations per car (search)
      stop: nominal                    # ec-solve: stop once as good as the nominal car
      reference: site                  # the ground points the reference-point law holds

The models validate the YAML (unknown keys are errors); :mod:`rvmsim.compensation` builds its
frozen dataclasses from them.  The law itself is documented there and in
docs/compensation.md.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

__all__ = ["CompensationSpec", "StationSpec", "COMPENSABLE_PARAMS", "DEFAULT_RANGES"]

#: The ISP parameters an EOL step may write per car: the view's rotation (the pans turn its
#: axis, the tilt rolls it) and the moves of the image (the H/V shifts of the image circle,
#: in input px; the advanced shifts of the view window, in output half-widths).
COMPENSABLE_PARAMS = ("h_pan", "v_pan", "tilt", "h_shift", "v_shift", "adv_h_shift",
                      "adv_v_shift")

#: The allowed per-car offsets of each parameter when the file gives none (``h_pan``: the
#: magnitude of the view axis's turn, degrees; the shifts in their own units).
DEFAULT_RANGES: dict[str, tuple[float, float]] = {
    "h_pan": (0.0, 3.0), "tilt": (-3.0, 3.0), "h_shift": (-40.0, 40.0),
    "v_shift": (-40.0, 40.0), "adv_h_shift": (-0.1, 0.1), "adv_v_shift": (-0.1, 0.1),
}

_Param = Literal["h_pan", "v_pan", "tilt", "h_shift", "v_shift", "adv_h_shift", "adv_v_shift"]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class StationSpec(_Model):
    """The EOL station: how well it measures the camera's pose (1 σ, per axis) and the body's
    edge on the capture (1 σ, px), at which load state the car stands on the line (a load
    state's name; default: the first), and what it does with a car whose EC margin is inside
    the station's uncertainty (``fail`` it, or ``accept`` it on its measured values)."""

    angle_sigma_deg: Annotated[float, Field(ge=0, le=5)] = 0.1
    position_sigma_mm: Annotated[float, Field(ge=0, le=100)] = 1.0
    edge_sigma_px: Annotated[float, Field(ge=0, le=20)] = 0.3
    measured_at: Annotated[str, Field(min_length=1, max_length=40)] | None = None
    marginal: Literal["fail", "accept"] = "fail"


class CompensationSpec(_Model):
    """What the EOL step writes (``params``), within which offsets (``ranges``), measured how
    well (``station``), chosen how (``law``: ``ec-solve``, every EC on the car's own picture
    within ``budget`` evaluations; ``reference-points``, ground points held in place), and
    which points the reference-point law holds (``reference``: ``site`` = the guideline ends
    and the bases of the test objects; ``ground`` = a grid of ground points over the RVM
    image; ec-solve starts from that law's values)."""

    params: Annotated[list[_Param], Field(min_length=1)] = ["h_pan", "v_pan", "tilt"]
    ranges: dict[str, tuple[float, float]] = {}
    station: StationSpec = StationSpec()
    reference: Literal["site", "ground"] = "site"
    #: A registered law's name (:data:`rvmsim.percar.LAWS`; checked where the model is used).
    law: Annotated[str, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_-]{0,39}$")] = "ec-solve"
    budget: Annotated[int, Field(ge=4, le=2000)] = 24
    stop: Literal["nominal", "never"] = "nominal"

    @field_validator("params")
    @classmethod
    def _params(cls, params: list[str]) -> list[str]:
        if len(set(params)) != len(params):
            raise ValueError(f"a parameter is named twice: {params}")
        if ("h_pan" in params) != ("v_pan" in params):
            raise ValueError("h_pan and v_pan go together (the view axis turns in any "
                             "direction): name both or neither")
        return params

    @field_validator("ranges")
    @classmethod
    def _ranges(cls, ranges: dict[str, tuple[float, float]]) -> dict[str, tuple[float, float]]:
        for name, (low, high) in ranges.items():
            if name == "v_pan":
                raise ValueError("v_pan is the direction of the view axis's turn; limit the "
                                 "turn with h_pan: [0, max]")
            if name not in COMPENSABLE_PARAMS:
                raise ValueError(f"{name!r} is not a parameter the EOL step can write "
                                 f"(one of {', '.join(COMPENSABLE_PARAMS)})")
            if low > high:
                raise ValueError(f"{name}: the range [{low:g}, {high:g}] is inverted "
                                 "(give [low, high])")
            if name == "h_pan" and low != 0:
                raise ValueError("h_pan: the turn of the view axis is a magnitude; give "
                                 "[0, max]")
            if not (low <= 0 <= high):
                raise ValueError(f"{name}: the range [{low:g}, {high:g}] must hold 0 (the "
                                 "platform setting itself)")
        return ranges

    @model_validator(mode="after")
    def _ranges_named(self) -> CompensationSpec:
        extra = sorted(set(self.ranges) - set(self.params))
        if extra:
            raise ValueError(f"ranges: {', '.join(extra)} is not among params "
                             f"({', '.join(self.params)})")
        return self
