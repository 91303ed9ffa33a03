"""Fisheye intrinsics from board captures (``rvmsim calibrate``), and existing
calibrations imported as Kannala-Brandt cameras.

Modules: :mod:`.board` (``--board`` specs), :mod:`.captures` (image files),
:mod:`.detect` (corner detection), :mod:`.counting` (the other counting's hint),
:mod:`.intrinsics` (``cv2.fisheye.calibrate`` with outlier corner and view rejection),
:mod:`.imports` (OpenCV / Kalibr / OCamCalib / camera-block files),
:mod:`.outputs` (JSON, coverage picture, camera block, ``--write-scene``), :mod:`.run`
(a calibration from captures, or imported, into an output folder: ``rvmsim calibrate``).
See ``docs/calibration.md``.
"""

from __future__ import annotations

from .board import BoardSpec, CalibrationInputError, parse_board_spec
from .captures import board_images, load_grey
from .detect import find_board_corners, find_board_view
from .imports import ImportedCamera, fit_kannala_brandt, import_calibration
from .intrinsics import BoardView, Calibration, ViewFit, calibrate_fisheye
from .outputs import camera_block, coverage_image, write_calibration_outputs, write_scene_camera
from .run import CalibrationSummary, calibrate_captures, import_camera

__all__ = [
    "BoardSpec", "CalibrationInputError", "parse_board_spec",
    "board_images", "load_grey", "find_board_corners", "find_board_view",
    "ImportedCamera", "fit_kannala_brandt", "import_calibration",
    "BoardView", "Calibration", "ViewFit", "calibrate_fisheye",
    "camera_block", "coverage_image", "write_calibration_outputs", "write_scene_camera",
    "CalibrationSummary", "calibrate_captures", "import_camera",
]
