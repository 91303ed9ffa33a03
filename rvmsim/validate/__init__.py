"""Validation of a scene against a real capture from the physical camera.

Modules, in the order :func:`validate` uses them:

- :mod:`.capture`: reading a capture (:func:`load_capture`) and its checks.
- :mod:`.landmarks`: the scene's checker corners the synthetic frame shows usably.
- :mod:`.board`: the calibration board's corner grid and square colours (:class:`BoardShade`).
- :mod:`.board_detect`, :mod:`.board_start`: the global start: the board (whole or a part of
  it) found by the chessboard detector without predicted corners, the readings of its grid
  decided by the squares' colours where they differ, and a planar PnP on it
  (:func:`search_board`, :func:`find_board_start`).
- :mod:`.matching`: finding them in the capture (chessboard detector, NCC + cornerSubPix).
- :mod:`.pose`: the mount pose fit (:func:`fit_pose`), the dense pre-alignment on the
  ground patterns' shade and the checker-shift disambiguation.
- :mod:`.edges`: Canny edges and their chamfer comparison (:func:`compare_edges`).
- :mod:`.rvm`: the capture and the synthetic frame through the ISP, and their ECs.
- :mod:`.verdict`: the result records (:class:`Validation`, ...) and the checks.
- :mod:`.scene_edit`: the scene with the corrected mount (:func:`scene_with_mount`,
  :func:`write_corrected_scene`).
- :mod:`.outputs`: the pictures, and writing them (the rest of the output folder:
  :func:`rvmsim.report.write_validation_outputs`).
- :mod:`.failure`: :class:`ValidationFailure`, the error naming the step that failed.
- :mod:`.validation`: :func:`validate`, the steps in order.
- :mod:`.projection`: scene points to pixels at a corrected pose (shared by the above).
- :mod:`.captures`: capture files validated one after another (:func:`validate_captures`,
  one :class:`CaptureOutcome` each: ``rvmsim validate``).
"""

from __future__ import annotations

from .board import BoardLayout, BoardShade, LatticeEvidence, board_layout
from .board_start import (
    BoardSearch,
    BoardStart,
    find_board_start,
    search_board,
)
from .capture import check_captures, load_capture
from .captures import (CAPTURE_SUFFIXES, CaptureOutcome, capture_files, capture_folders,
                       validate_captures)
from .edges import CHAMFER_TRUNCATE_PX, compare_edges
from .failure import ValidationFailure
from .matching import find_landmarks
from .outputs import write_pictures
from .pose import fit_pose
from .scene_edit import scene_with_mount, write_corrected_scene
from .validation import ValidationSettings, validate
from .verdict import (
    Check,
    EdgeComparison,
    LandmarkMatch,
    PoseCorrection,
    RvmComparison,
    Tolerances,
    Validation,
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
    "check_captures",
    "find_landmarks",
    "fit_pose",
    "compare_edges",
    "validate",
    "ValidationSettings",
    "write_corrected_scene",
    "scene_with_mount",
    "CHAMFER_TRUNCATE_PX",
    "ValidationFailure",
    "BoardLayout",
    "BoardShade",
    "board_layout",
    "BoardStart",
    "BoardSearch",
    "LatticeEvidence",
    "find_board_start",
    "search_board",
    "write_pictures",
    "CAPTURE_SUFFIXES",
    "CaptureOutcome",
    "capture_files",
    "capture_folders",
    "validate_captures",
]
