"""Production variation: mount tolerances and load states, quasi-random samples of them,
their fisheye images (rotations re-folded, few renders) and the yield of an ISP setting.

Modules: :mod:`.variation` (the variation model), :mod:`.samples` (Sobol draws),
:mod:`.images` (sample images), :mod:`.stats` (yield, confidence interval, what drives
failures), :mod:`.sensitivity` (each EC's value as a formula of the offsets and load),
:mod:`.robustness` (:func:`robustness`), :mod:`.markets` (the yield per market,
:func:`markets_robustness`), :mod:`.export` (a sample as a scene file),
:mod:`.guideline_errors` (the parking guidelines' errors over a fleet after compensation).
See docs/robustness.md.
"""

from __future__ import annotations

from .variation import (
    AxisDistribution,
    LoadState,
    Variation,
    load_variation,
    variation_from_scene,
    variation_from_spec,
    variation_for,
    NOMINAL_LOAD,
)
from .samples import MountSample, draw_samples, nominal_sample, position_levels_at
from .images import (sample_images, sample_camera, body_pose, cover_for, Refolder, refolder,
                     SampleSet, sample_rvm_labels, viewpoint_groups, render_viewpoints)
from .stats import (
    YieldEstimate,
    yield_estimate,
    wilson_interval,
    AxisEffect,
    failure_drivers,
    ec_margins,
    limiting_ec,
)
from .compensated import (COMPENSATION_CHUNK, CarJudge, CompensatedSamples, StationReading,
                          read_at_station, station_readings, station_twin, true_deviation)
from .sensitivity import Sensitivity, fit_sensitivity, sensitivity_axes, GOOD_R2
from .export import SampleExport, sample_scene_document, write_sample_scenes
from .robustness import (
    EcStats,
    ScalePoint,
    RobustnessResult,
    RobustnessSettings,
    evaluate_samples,
    robustness,
    DEFAULT_SCALES,
)
from .markets import MarketYield, MarketsRobustness, markets_robustness
from .guideline_errors import FleetGuidelines, GuidelineErrors, fleet_guideline_errors

__all__ = [
    "AxisDistribution",
    "LoadState",
    "Variation",
    "load_variation",
    "variation_from_scene",
    "variation_from_spec",
    "variation_for",
    "NOMINAL_LOAD",
    "MountSample",
    "draw_samples",
    "nominal_sample",
    "render_viewpoints",
    "position_levels_at",
    "sample_images",
    "sample_camera",
    "body_pose",
    "cover_for",
    "Refolder",
    "refolder",
    "SampleSet",
    "sample_rvm_labels",
    "viewpoint_groups",
    "YieldEstimate",
    "yield_estimate",
    "wilson_interval",
    "AxisEffect",
    "failure_drivers",
    "ec_margins",
    "CompensatedSamples",
    "CarJudge",
    "StationReading",
    "read_at_station",
    "station_twin",
    "COMPENSATION_CHUNK",
    "station_readings",
    "true_deviation",
    "Sensitivity",
    "fit_sensitivity",
    "sensitivity_axes",
    "GOOD_R2",
    "SampleExport",
    "sample_scene_document",
    "write_sample_scenes",
    "EcStats",
    "ScalePoint",
    "RobustnessResult",
    "RobustnessSettings",
    "evaluate_samples",
    "robustness",
    "DEFAULT_SCALES",
    "MarketYield",
    "MarketsRobustness",
    "markets_robustness",
    "limiting_ec",
    "FleetGuidelines",
    "GuidelineErrors",
    "fleet_guideline_errors",
]
