"""Evaluation criteria (ECs): measurements of the RVM label image, sigmoid scores, drawings."""

from __future__ import annotations

from .core import (
    EC_IDS,
    criteria_from_text,
    EcDefinition,
    EC_DEFINITIONS,
    Sigmoid,
    Criterion,
    Criteria,
    Measurements,
    EcValue,
    EcResult,
    EcBatch,
    score_batch,
    values_array,
    measure,
    measure_source,
    LabelSource,
    GROUPS,
    score,
    evaluate,
    load_criteria,
    default_criteria,
)
from .annotate import (
    annotate,
)
from .evaluator import (
    CandidateEvaluator,
)

__all__ = [
    "EC_IDS",
    "criteria_from_text",
    "EcDefinition",
    "EC_DEFINITIONS",
    "Sigmoid",
    "Criterion",
    "Criteria",
    "Measurements",
    "EcValue",
    "EcResult",
    "EcBatch",
    "score_batch",
    "values_array",
    "measure",
    "measure_source",
    "LabelSource",
    "GROUPS",
    "score",
    "evaluate",
    "load_criteria",
    "default_criteria",
    "annotate",
    "CandidateEvaluator",
]
