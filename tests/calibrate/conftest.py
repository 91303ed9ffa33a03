"""Rendered board views for the calibration tests: a Kannala-Brandt camera (fx ≠ fy,
off-centre principal point) in a board-only scene, the board held at 12 poses up to ~80°
off-axis (small renders, real pyrender)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rvmsim.camera import rotation_from_ypr
from rvmsim.render import render_fisheye
from rvmsim.scene import Scene, scene_from_dict

CAMERA = {
    "image_size": [640, 480],
    "intrinsics": {"fx": 200.0, "fy": 203.0, "cx": 322.3, "cy": 236.8},
    "lens": {"model": "kannala_brandt", "k": [-0.03, 0.004, -0.002, 0.0002], "fov_deg": 196},
    "mount": {"position": [0.0, -1.2, 0.0]},
}
#: (off-axis angle, azimuth in the image (0 = right, 90 = down), distance m, tilt yaw,
#: tilt pitch, roll), degrees.
POSES = [
    (0, 0, 0.8, 0, 0, 0), (0, 0, 0.9, 30, -20, 10), (25, 0, 0.85, -20, 15, 5),
    (25, 180, 0.85, 25, -10, -8), (30, 90, 0.8, 10, 25, 0), (30, 270, 0.8, -10, -25, 12),
    (45, 45, 0.75, 15, 15, -5), (45, 225, 0.75, -15, -15, 6), (60, 0, 0.7, -25, 0, 10),
    (60, 180, 0.7, 25, 5, -10), (70, 10, 0.65, -35, 10, 0), (70, 190, 0.65, 35, -10, 5),
]
SQUARES = (8, 10)
SQUARE = 0.05


def board_pose(off_deg: float, az_deg: float, dist: float, tilt_yaw: float,
               tilt_pitch: float, roll: float) -> dict:
    """A free board facing the camera at ``off_deg`` off its axis, tilted."""
    t, a = math.radians(off_deg), math.radians(az_deg)
    d_cam = np.array([math.sin(t) * math.cos(a), math.sin(t) * math.sin(a), math.cos(t)])
    r_cam = rotation_from_ypr(0.0, 0.0, 0.0)
    d = r_cam @ d_cam
    centre = np.array(CAMERA["mount"]["position"]) + dist * d
    # The board's "forward" (−normal, R @ +Z) points away from the camera along d.
    yaw = math.degrees(math.atan2(d[0], d[2]))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, d[1]))))
    r = rotation_from_ypr(yaw, pitch, 0.0)
    assert np.allclose(r @ [0, 0, 1.0], d, atol=1e-9)
    return {"placement": "free", "position": [float(x) for x in centre],
            "yaw_deg": float(np.clip(yaw + tilt_yaw, -180, 180)),
            "pitch_deg": float(np.clip(pitch + tilt_pitch, -90, 90)), "roll_deg": float(roll),
            "squares": list(SQUARES), "square_size": SQUARE, "margin": 0.03}


def board_scene(pose: dict) -> Scene:
    return scene_from_dict({"name": "board", "camera": CAMERA,
                            "test_site": {"fmvss": False, "board": pose}}, base_dir=".")


@pytest.fixture(scope="session")
def board_views(tmp_path_factory) -> list[Path]:
    """The 12 rendered views as PNG files (colour renders)."""
    import imageio.v3 as iio

    folder = tmp_path_factory.mktemp("board_views")
    out = []
    for k, p in enumerate(POSES):
        img = render_fisheye(board_scene(board_pose(*p))).color
        path = folder / f"view_{k:02d}.png"
        iio.imwrite(path, img)
        out.append(path)
    return out


@pytest.fixture(scope="session")
def detected_views(board_views):
    """The board's corners found in each rendered view (rvmsim.calibrate's detector)."""
    from rvmsim.calibrate import BoardView, BoardSpec, find_board_corners, load_grey

    board = BoardSpec((SQUARES[0] - 1, SQUARES[1] - 1), SQUARE)
    views = []
    for p in board_views:
        c = find_board_corners(load_grey(p), board)
        assert c is not None, f"board not found in {p.name}"
        views.append(BoardView(p.name, c))
    return board, views


#: The ChArUco board of the ChArUco views: 7 × 10 squares of 0.08 m, 0.06 m markers.
CHARUCO = {"pattern": "charuco", "squares": [7, 10], "square_size": 0.08,
           "marker_size": 0.06}


@pytest.fixture(scope="session")
def charuco_views(tmp_path_factory) -> list[Path]:
    """The 12 poses with a ChArUco board instead, as PNG files (some show only part of
    it: at 60-70° off-axis it reaches past the field)."""
    import imageio.v3 as iio

    folder = tmp_path_factory.mktemp("charuco_views")
    out = []
    for k, p in enumerate(POSES):
        pose = {**board_pose(*p), **CHARUCO}
        img = render_fisheye(board_scene(pose)).color
        path = folder / f"charuco_{k:02d}.png"
        iio.imwrite(path, img)
        out.append(path)
    return out
