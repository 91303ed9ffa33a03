"""The schema of ``robustness.json`` (:meth:`~rvmsim.robust.RobustnessResult.as_dict`) as it
is read back (``rvmsim signoff``, ``rvmsim report``): the keys and the types its readers use.
A key a reader finds with a default may be absent (a file of an earlier rvmsim); when present
it must be of its type.  Other keys are allowed.  ``tests/bad_input/test_result_files.py``
checks that what ``rvmsim robustness`` writes validates."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import Field

from .._io import FilePathText, ReadModel

__all__ = ["RobustnessFile", "YieldEstimateDoc"]

#: A finite number (a yield, an interval end).
Finite = Annotated[float, Field(allow_inf_nan=False)]
#: A share: a finite number in [0, 1].
Share = Annotated[float, Field(ge=0.0, le=1.0, allow_inf_nan=False)]
#: A pair (low, high), either end null for an open range.
Range = Annotated[list[float | None], Field(min_length=2, max_length=2)]


class YieldEstimateDoc(ReadModel):
    """A yield with its 95 % interval (``yield``, ``ci95``, ``n_pass``, ``n``)."""

    yield_: Share = Field(alias="yield")
    ci95: Annotated[list[Share], Field(min_length=2, max_length=2)]
    n_pass: int = 0
    n: int = 0


class _MountAxis(ReadModel):
    kind: str = ""
    half_width: float = 0.0
    sigma: float = 0.0
    truncate: float = 3.0


class _LoadState(ReadModel):
    name: str = ""
    height_mm: float = 0.0
    pitch_deg: float = 0.0
    probability: float = 1.0


class _Variation(ReadModel):
    source: str = ""
    position_levels: int | None = None
    mount: dict[str, _MountAxis] = {}
    load_states: list[_LoadState] = []
    min_yield: Share | None = None


class _AxisEffect(ReadModel):
    axis: str = ""
    states: list[str] = []
    failure_rates: list[float] = []
    spread: float = 0.0


class _EcRow(ReadModel):
    id: str
    name: str = ""
    unit: str = ""
    range: Range = [None, None]
    enabled: bool = True
    n_fail: int = 0
    failure_rate: Share = 0.0
    worst_value: float | None = None
    worst_margin: float | None = None
    worst_sample: int | None = None
    driver: str | None = None
    axes: list[_AxisEffect] = []
    sensitivity: dict[str, Any] | None = None


class _Limiting(ReadModel):
    id: str | None = None
    name: str = ""
    n_fail: int = 0
    failure_rate: Share = 0.0


class _ScalePoint(YieldEstimateDoc):
    scale: float


class _CompensationStation(ReadModel):
    angle_sigma_deg: float = 0.0
    position_sigma_mm: float = 0.0
    edge_sigma_px: float = 0.0
    measured_at: str | None = None
    marginal: str = ""


class _Compensation(ReadModel):
    source: str = ""
    params: list[str] = []
    ranges: dict[str, Range] = {}
    station: _CompensationStation | None = None
    reference: str = ""
    law: str = ""
    budget: int | None = None
    stop: str | None = None
    reference_points: int = 0
    offsets: dict[str, dict[str, float | list[float]]] = {}
    n_out_of_range: int = 0
    residual_rms_px: dict[str, float] = {}
    verdicts: dict[str, int] = {}
    n_rejected: int = 0
    evaluations_per_car: dict[str, float] = {}


class _BeforeEc(ReadModel):
    id: str
    n_fail: int = 0
    failure_rate: Share = 0.0
    worst_value: float | None = None
    worst_margin: float | None = None


class _Before(YieldEstimateDoc):
    by_load: dict[str, YieldEstimateDoc] = {}
    limiting: _Limiting | None = None
    ecs: list[_BeforeEc] = []


class _Correction(ReadModel):
    values: dict[str, float] = {}
    offsets: dict[str, float] = {}
    within_range: bool = True
    exceeded: list[str] = []
    residual_rms_px: float | None = None
    residual_max_px: float | None = None


class _StationEc(ReadModel):
    value: float | None = None
    margin: float | None = None
    sigma: float | None = None


class _SampleStation(ReadModel):
    law: str = ""
    status: str = ""
    reasons: list[str] = []
    evaluations: int = 0
    station_ecs: dict[str, _StationEc] = {}
    accepted: bool = True


class _Sample(ReadModel):
    index: int
    load: str = ""
    x_mm: float = 0.0
    y_mm: float = 0.0
    z_mm: float = 0.0
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    render_position_mm: list[float] = []
    ec_score: float | None = None
    passed: bool = True
    failed: list[str] = []
    passed_before_compensation: bool | None = None
    measured_deviation: dict[str, float] = {}
    correction: _Correction | None = None
    station: _SampleStation | None = None


class _InputFile(ReadModel):
    role: str = "file"
    path: FilePathText | None = None
    sha256: str | None = None
    note: str = ""


class _Inputs(ReadModel):
    files: list[_InputFile] | None = None
    render_scale: float | None = None
    params_file: FilePathText | None = None
    variation_file: FilePathText | None = None
    criteria_file: FilePathText | None = None
    compensation: str | None = None
    markets: str | list[str] | None = None


class RobustnessFile(YieldEstimateDoc):
    """``robustness.json`` as its readers use it (see the module docstring)."""

    n_pass: int
    n: int
    scene: FilePathText
    vehicle: str = ""
    criteria: str = ""
    isp: dict[str, Any]
    judged_at: list[int] | None = None
    seed: int
    variation: _Variation
    min_yield: Share | None = None
    meets_min_yield: bool | None = None
    nominal: dict[str, Any] | None = None
    worst_sample: int | None = None
    ecs: list[_EcRow]
    limiting: _Limiting | None = None
    yield_by_load: dict[str, YieldEstimateDoc]
    scale_curve: list[_ScalePoint] = []
    compensation: _Compensation | None = None
    yield_before_compensation: _Before | None = None
    samples: list[_Sample]
    timings_s: dict[str, float] = {}
    inputs: _Inputs = _Inputs()
