"""Evaluation criteria (ECs): a registry of ECs, the paper's eleven, their measurement on the
RVM label image, sigmoid scores, drawings and the fast tuning evaluator.

Modules: :mod:`.registry` (what an EC is, plugins), :mod:`.hooks` (an EC's optional
closed-form sub-solve and feasibility reason), :mod:`.solves` and :mod:`.feasibility` (those
of the paper's ECs, and their helpers), :mod:`.context` (the scene and ISP map
an EC may read besides the labels), :mod:`.fmvss111` and :mod:`.objects` (ECs 1-5, 1-6,
6-1: FMVSS 111 beyond the paper, a plugin), :mod:`.groups` (label groups, windows),
:mod:`.measure` (label sources and helpers for measure functions), :mod:`.builtin` (the
paper's eleven, a plugin like any other), :mod:`.sigmoid` and :mod:`.scoring` (scores,
criteria, results), :mod:`.config` (criteria files), :mod:`.image` (whole-image measure and
evaluate), :mod:`.annotate`, :mod:`.evaluator`.  See docs/criteria.md.
"""

from __future__ import annotations

from typing import Any

from .groups import (
    EMPTY_WINDOW,
    LabelGroup,
    Window,
    group_windows,
)
from .measure import (
    EcFailedError,
    LabelSource,
    Measurement,
    Measurements,
    MeasureOptions,
    bounding_box,
    call_ec,
    count_label,
    label_mask,
    offset,
)
from .stack import (
    LabelStack,
    StackMeasureFn,
    measure_stack_ecs,
    stack_boxes,
    stack_counts,
    stack_mask,
)
from .sigmoid import (
    Criterion,
    Sigmoid,
)
from .hooks import (
    InfeasibilityFn,
    SolveFn,
    SolveStackFn,
    StackParams,
    SubSolve,
    TargetFn,
    range_middle,
    range_zero,
)
from .solves import (
    outline_points,
)
from .registry import (
    BUILTIN_PLUGIN,
    EC_IDS,
    ENTRY_POINT_GROUP,
    EcDefinition,
    builtin_ecs,
    checked_solve_value,
    load_plugin,
    resolve_plugin,
)
from .context import (
    IspView,
    SceneContext,
    scene_context,
)
from .feasibility import (
    PATCH_SAMPLES,
    LabelsAbsent,
    PatchView,
    label_counts,
    patch_view,
)
from .support import (
    ONLY_SUPPORTED_HINT,
    Unsupported,
    check_supported,
    ec_needs,
    label_left_out,
    supported_criteria,
    unsupported_ecs,
)
from .scoring import (
    Criteria,
    EcBatch,
    EcResult,
    EcValue,
    score,
    score_batch,
    values_array,
)
from .values import is_yes_no
from .config import (
    BUNDLED_CRITERIA,
    bundled_criteria_text,
    criteria_reference,
    criteria_from_text,
    default_criteria,
    load_criteria,
)
from .image import (
    evaluate,
    measure,
    measure_labels,
    measure_source,
)
from .annotate import (
    FAIL,
    INK,
    OFF,
    PASS,
    Canvas,
    annotate,
)
from .record import (
    NEAR_SCORE,
    could_pass,
    pixel_scales,
    record_display,
    record_size,
    to_record_units,
)

__all__ = [
    "EC_IDS",
    "EC_DEFINITIONS",
    "GROUPS",
    "BUILTIN_PLUGIN",
    "ENTRY_POINT_GROUP",
    "EcDefinition",
    "EcFailedError",
    "call_ec",
    "builtin_ecs",
    "load_plugin",
    "resolve_plugin",
    "SubSolve",
    "SolveFn",
    "SolveStackFn",
    "StackParams",
    "TargetFn",
    "InfeasibilityFn",
    "range_middle",
    "range_zero",
    "outline_points",
    "checked_solve_value",
    "PATCH_SAMPLES",
    "PatchView",
    "patch_view",
    "LabelsAbsent",
    "label_counts",
    "LabelGroup",
    "Window",
    "EMPTY_WINDOW",
    "group_windows",
    "LabelSource",
    "LabelStack",
    "StackMeasureFn",
    "measure_stack_ecs",
    "stack_boxes",
    "stack_counts",
    "stack_mask",
    "Measurement",
    "Measurements",
    "MeasureOptions",
    "bounding_box",
    "count_label",
    "label_mask",
    "offset",
    "Sigmoid",
    "Criterion",
    "Criteria",
    "EcValue",
    "is_yes_no",
    "EcResult",
    "EcBatch",
    "score_batch",
    "score",
    "values_array",
    "criteria_from_text",
    "BUNDLED_CRITERIA",
    "bundled_criteria_text",
    "criteria_reference",
    "SceneContext",
    "IspView",
    "scene_context",
    "load_criteria",
    "default_criteria",
    "measure",
    "measure_source",
    "measure_labels",
    "evaluate",
    "annotate",
    "Canvas",
    "PASS",
    "FAIL",
    "OFF",
    "INK",
    "NEAR_SCORE",
    "record_display",
    "record_size",
    "pixel_scales",
    "to_record_units",
    "could_pass",
    "ONLY_SUPPORTED_HINT",
    "Unsupported",
    "check_supported",
    "ec_needs",
    "label_left_out",
    "supported_criteria",
    "unsupported_ecs",
]


def __getattr__(name: str) -> Any:
    # The paper's ECs are a plugin (.builtin), loaded on first use, so that it can import
    # this package's public API like any customer's plugin.
    if name == "EC_DEFINITIONS":
        return builtin_ecs()
    if name == "GROUPS":
        return {g.name: g.labels for ec in builtin_ecs() for g in ec.groups}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
