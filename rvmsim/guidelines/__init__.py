"""Parking guidelines through the warp: distance marks, width lines and steering-dependent
trajectory lines from the car's geometry, drawn through the camera's lens and the ISP map into
the RVM image of record, checked against lines painted on the rendered site.

Modules: :mod:`.kinematics` (the car reversing: a single-track model), :mod:`.lines` (the
lines on the ground), :mod:`.project` (ground → display px, cut at the picture's border),
:mod:`.overlay` (:func:`compute_guidelines`: one car's set).  See docs/guidelines.md.
"""

from __future__ import annotations

from .kinematics import RunningGear, running_gear, has_running_gear, reverse_paths
from .lines import GroundLine, static_lines, trajectory_lines, half_width_m
from .project import GuidelineView, DisplayPiece, DisplayLine, project_lines
from .overlay import (GuidelineSet, scene_spec, guideline_output, guideline_view,
                      compute_guidelines, steering_angles)

__all__ = [
    "RunningGear",
    "running_gear",
    "has_running_gear",
    "reverse_paths",
    "GroundLine",
    "static_lines",
    "trajectory_lines",
    "half_width_m",
    "GuidelineView",
    "DisplayPiece",
    "DisplayLine",
    "project_lines",
    "GuidelineSet",
    "scene_spec",
    "guideline_output",
    "guideline_view",
    "compute_guidelines",
    "steering_angles",
]
