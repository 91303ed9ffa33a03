"""Validation of a scene against a real capture from the physical camera.

Modules, in the order :func:`validate` uses them:

- the pose search, :func:`rvmsim.pose.find_mount` (its own package: ``rvmsim eol`` and
  ``rvmsim calibrate`` use it too): the scene's checker corners found in the capture and the
  mount pose fitted.
- :mod:`.edges`: Canny edges and their chamfer comparison (:func:`compare_edges`).
- :mod:`.rvm`: the capture and the synthetic frame through the ISP, and their ECs.
- :mod:`.verdict`: the result records (:class:`Validation`, ...) and the checks.
- :mod:`.scene_edit`: the scene file with the corrected mount (:func:`write_corrected_scene`).
- :mod:`.outputs`: the pictures, and writing them (the rest of the output folder:
  :func:`rvmsim.report.write_validation_outputs`).
- :mod:`.failure`: :class:`ValidationFailure`, the error naming the step that failed.
- :mod:`.validation`: :func:`validate`, the steps in order.
- :mod:`.captures`: capture files validated one after another (:func:`validate_captures`,
  one :class:`CaptureOutcome` each: ``rvmsim validate``).
"""

from __future__ import annotations

from .captures import CaptureOutcome, validate_captures
from .edges import CHAMFER_TRUNCATE_PX, compare_edges
from .failure import ValidationFailure
from .outputs import write_pictures
from .scene_edit import write_corrected_scene
from .validation import ValidationSettings, validate
from .verdict import Check, EdgeComparison, RvmComparison, Tolerances, Validation

__all__ = [
    "Tolerances",
    "EdgeComparison",
    "RvmComparison",
    "Check",
    "Validation",
    "compare_edges",
    "validate",
    "ValidationSettings",
    "write_corrected_scene",
    "CHAMFER_TRUNCATE_PX",
    "ValidationFailure",
    "write_pictures",
    "CaptureOutcome",
    "validate_captures",
]
