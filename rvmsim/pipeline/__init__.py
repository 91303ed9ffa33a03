"""Rendered fisheye images → RVM images → ECs: the evaluation paths and the one factory that
chooses among them.

Modules: :mod:`.frame` (:func:`evaluate_params`, the full path: one candidate's RVM colour
and label images, ECs and annotated image; :func:`render_rvm`), :mod:`.factory`
(:func:`make_evaluator`: the evaluator of one image for many candidates, of a batch of
images for one setting, or of a run's members, on the fastest exact path the criteria
allow; the classes in :mod:`.evaluators`), :mod:`.record_rule` (search size → size of
record), :mod:`.pixels` (the
fisheye pixels an RVM image shows), :mod:`.files` (what ``render``, ``process`` and
``evaluate`` write).
"""

from __future__ import annotations

from .frame import RvmFrame, evaluate_params, evaluate_rvm_labels, render_rvm, rvm_color
from .pixels import RvmPixels, rvm_pixels
from .candidate import CandidateEvaluator
from .candidate_batch import CandidateBatch
from .batched import ImagesEvaluator
from .evaluators import (
    EvaluationPath,
    FisheyeLabels,
    FisheyeSet,
    FullEvaluator,
    ImageEvaluator,
    RecordEvaluator,
    SetEvaluator,
)
from .factory import make_evaluator, record_output
from .record_rule import RecordRule
from .files import write_evaluation, write_fisheye, write_frame, write_processed

__all__ = [
    "CandidateEvaluator",
    "CandidateBatch",
    "ImagesEvaluator",
    "RvmFrame",
    "evaluate_params",
    "evaluate_rvm_labels",
    "render_rvm",
    "rvm_color",
    "RvmPixels",
    "rvm_pixels",
    "EvaluationPath",
    "FisheyeLabels",
    "FisheyeSet",
    "FullEvaluator",
    "ImageEvaluator",
    "RecordEvaluator",
    "SetEvaluator",
    "make_evaluator",
    "RecordRule",
    "record_output",
    "write_evaluation",
    "write_fisheye",
    "write_frame",
    "write_processed",
]
