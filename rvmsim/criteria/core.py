"""Compatibility: the names ``rvmsim.criteria.core`` had before the EC registry.

Import from :mod:`rvmsim.criteria` instead; this module only re-exports (until the callers
in other packages have moved).
"""

from __future__ import annotations

from . import (
    EC_IDS,
    Criteria,
    Criterion,
    EcBatch,
    EcDefinition,
    EcResult,
    EcValue,
    LabelSource,
    Measurements,
    Sigmoid,
    Window,
    criteria_from_text,
    default_criteria,
    evaluate,
    load_criteria,
    measure,
    measure_source,
    score,
    score_batch,
    values_array,
)

__all__ = ["EC_IDS", "Criteria", "Criterion", "EcBatch", "EcDefinition", "EcResult", "EcValue",
           "LabelSource", "Measurements", "Sigmoid", "Window", "criteria_from_text",
           "default_criteria", "evaluate", "load_criteria", "measure", "measure_source",
           "score", "score_batch", "values_array"]
