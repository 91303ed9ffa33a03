"""Finding the camera's mount pose in a capture: ``rvmsim validate``, ``rvmsim eol`` (a car
at the station) and ``rvmsim calibrate`` (the board's corners) share it.

Modules, in the order :func:`find_mount` uses them:

- :mod:`.capture`: reading a capture (:func:`load_capture`), its checks, and the capture
  files a command is given (:func:`capture_files`).
- :mod:`.landmarks`: the scene's checker corners the synthetic frame shows usably.
- :mod:`.charuco`: a ChArUco board's corners, named by its markers.
- :mod:`.board`: the calibration board's corner grid and square colours (:class:`BoardShade`).
- :mod:`.board_detect`, :mod:`.board_start`: the global start: the board (whole or a part of
  it) found by the chessboard detector without predicted corners, the readings of its grid
  decided by the squares' colours where they differ, and a planar PnP on it
  (:func:`search_board`, :func:`find_board_start`).
- :mod:`.shade_search`: with ground patterns, the global search on their shade.
- :mod:`.matching`: finding the corners in the capture (chessboard detector, NCC +
  cornerSubPix).
- :mod:`.fit`: the mount pose fit (:func:`fit_pose`), the dense pre-alignment on the
  ground patterns' shade and the checker-shift disambiguation.
- :mod:`.projection`: scene points to pixels at a corrected pose.
- :mod:`.records`: :class:`LandmarkMatch`, :class:`PoseCorrection`.
- :mod:`.mount`: the scene with the corrected mount (:func:`scene_with_mount`).
- :mod:`.pictures`: the landmarks and the board drawn on the capture.
- :mod:`.failure`: :class:`PoseFailure`, the error naming the step that failed.
- :mod:`.find`: :func:`find_mount`, the steps in order.
"""

from __future__ import annotations

from .board import BoardLayout, BoardShade, LatticeEvidence, board_layout
from .board_start import BoardSearch, BoardStart, find_board_start, search_board
from .capture import (CAPTURE_SUFFIXES, capture_files, capture_folders, check_captures, grey,
                      load_capture)
from .charuco import CharucoPattern, detect_charuco
from .failure import PoseFailure
from .find import MountFit, PoseSettings, find_mount, render_corrected
from .fit import fit_pose
from .landmarks import VisibleLandmarks, visible_landmarks
from .matching import find_landmarks
from .mount import mount_correction, scene_with_mount
from .pictures import blend, board_picture, landmark_picture
from .records import LandmarkMatch, PoseCorrection

__all__ = [
    "find_mount",
    "PoseSettings",
    "MountFit",
    "PoseFailure",
    "LandmarkMatch",
    "PoseCorrection",
    "render_corrected",
    "scene_with_mount",
    "mount_correction",
    "VisibleLandmarks",
    "visible_landmarks",
    "find_landmarks",
    "fit_pose",
    "BoardLayout",
    "BoardShade",
    "LatticeEvidence",
    "board_layout",
    "BoardStart",
    "BoardSearch",
    "find_board_start",
    "search_board",
    "CharucoPattern",
    "detect_charuco",
    "load_capture",
    "check_captures",
    "grey",
    "CAPTURE_SUFFIXES",
    "capture_files",
    "capture_folders",
    "blend",
    "board_picture",
    "landmark_picture",
]
