"""Validation of a scene against a real capture from the physical camera."""

from __future__ import annotations

from .core import (
    Tolerances,
    LandmarkMatch,
    PoseCorrection,
    EdgeComparison,
    RvmComparison,
    Check,
    Validation,
    load_capture,
    find_landmarks,
    fit_pose,
    compare_edges,
    validate,
    write_outputs,
    write_corrected_scene,
    scene_with_mount,
    CHAMFER_TRUNCATE_PX,
)

__all__ = [
    "Tolerances",
    "LandmarkMatch",
    "PoseCorrection",
    "EdgeComparison",
    "RvmComparison",
    "Check",
    "Validation",
    "load_capture",
    "find_landmarks",
    "fit_pose",
    "compare_edges",
    "validate",
    "write_outputs",
    "write_corrected_scene",
    "scene_with_mount",
    "CHAMFER_TRUNCATE_PX",
]
