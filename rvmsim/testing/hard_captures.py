"""Hard rendered board captures for the validation start (issue 28; not a test module:
tests/validate/test_hard_starts.py and tools/bench_starts.py use it).

Each case is a board-only scene (vehicle A's body, no test objects or guidelines) with a
checkerboard where the team saw the whole-board start fail on real cameras: close and cut by
the image border, near the fisheye edge, partly outside the lens's field, and close boards of
the three symmetry kinds (7 × 9: half-turn symmetric, 7 × 10: odd × even, 8 × 6: even × even).
Every case has its own camera (fx ≠ fy, off-centre principal point, its own Kannala-Brandt
k and field of view), so no test leans on one lens.  The capture is the scene rendered at
its true mount and degraded like a sensor (:func:`.captures.degrade`).

The true inner corners are computed here from the board's fields alone (not with
:mod:`rvmsim.scene`) and projected with ``cv2.fisheye.projectPoints``, an independent check
of where the render put the board.
"""

from __future__ import annotations

import copy
import functools
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import yaml
from scipy.spatial.transform import Rotation

from rvmsim.render import FisheyeImages, render_fisheye
from rvmsim.scene import Scene

from .captures import degrade, make_scene
from .scenes import SCENES

#: The squares stand this far in front of an upright board's plate, and a ground board's
#: plate lies this far above the ground (m; rvmsim/scene/site.py's BOARD_SQUARE_LIFT_M and
#: BOARD_LIFT_M, the geometry the renderer draws).
SQUARE_LIFT_M = 0.003
GROUND_PLATE_M = 0.006


@dataclass(frozen=True)
class HardCase:
    """A hard board capture's scene.

    Attributes
    ----------
    name : str
    what : str
        What makes it hard, in words.
    camera : dict
        ``camera`` of the scene file without its mount: image size (px), intrinsics (px),
        Kannala-Brandt lens (k1..k4, fov degrees).
    mount : dict
        The true mount: position (m), yaw/pitch/roll (degrees).
    board : dict
        ``test_site.board`` of the scene file.
    whole_board_found : bool
        Whether ``cv2.findChessboardCornersSB`` finds the whole board in the capture (the
        start the validation had before issue 28 works only then).
    seed : int
        The degradation's noise and texture seed.
    """

    name: str
    what: str
    camera: dict
    mount: dict
    board: dict
    whole_board_found: bool = False
    seed: int = 0


def _camera(size: tuple[int, int], fx: float, fy: float, cx: float, cy: float,
            k: tuple[float, float, float, float], fov: float) -> dict:
    return {"image_size": list(size), "intrinsics": {"fx": fx, "fy": fy, "cx": cx, "cy": cy},
            "lens": {"model": "kannala_brandt", "k": list(k), "fov_deg": fov}}


def _mount(pos: tuple[float, float, float], yaw: float, pitch: float, roll: float) -> dict:
    return {"position": list(pos), "yaw_deg": yaw, "pitch_deg": pitch, "roll_deg": roll}


def _board(squares: tuple[int, int], size_m: float, pos: tuple[float, float, float],
           yaw: float = 0.0, placement: str = "upright", margin: float = 0.03) -> dict:
    return {"placement": placement, "position": list(pos), "yaw_deg": yaw,
            "squares": list(squares), "square_size": size_m, "margin": margin}


#: A lens whose field the 640 × 480 sensor crops (about ±62° across, ±48° up and down).
_NARROW = _camera((640, 480), 296.0, 287.0, 331.4, 229.2, (-0.021, 0.004, -0.0012, 0.0), 186)
#: A wide lens: the whole 200° circle across the sensor's width.
_WIDE = _camera((640, 480), 166.0, 171.5, 311.6, 247.3, (-0.048, 0.0065, -0.0021, 0.0003), 200)
#: A 180° lens whose image circle lies inside a 512 × 384 sensor.
_CIRCLE = _camera((512, 384), 118.0, 121.5, 259.3, 188.6, (-0.032, 0.002, 0.0, 0.0), 180)

CASES: dict[str, HardCase] = {c.name: c for c in (
    HardCase("cut_one_side", "7 x 10 board 0.6 m away, turned to the camera, its right "
             "column of squares and one column of inner corners cut by the right border",
             _NARROW, _mount((0.02, -1.0, -0.1), 2.0, 24.0, -0.8),
             _board((7, 10), 0.06, (0.5, -0.8, 0.3), yaw=35.0), seed=11),
    HardCase("cut_two_sides", "7 x 9 board 0.7 m away, turned to the camera, 17 of its 48 "
             "inner corners cut by the left and top borders",
             _NARROW, _mount((0.0, -0.95, -0.1), -1.5, 30.0, 1.2),
             _board((7, 9), 0.07, (-0.6, -1.15, 0.35), yaw=-30.0), seed=12),
    HardCase("fisheye_edge", "8 x 6 board 48-95 deg off the optical axis at the rim of a "
             "200 deg lens's circle, strongly curved",
             _WIDE, _mount((0.0, -1.0, -0.1), 3.0, 28.0, 0.5),
             _board((8, 6), 0.08, (0.6, -0.9, 0.0), yaw=50.0), seed=13),
    HardCase("outside_fov", "7 x 10 board 55-99 deg off the axis of a 180 deg lens: 8 of "
             "its inner corners beyond the lens's field",
             _CIRCLE, _mount((0.0, -1.0, -0.1), -2.0, 30.0, 0.0),
             _board((7, 10), 0.07, (-0.6, -0.85, -0.05), yaw=-50.0), seed=14),
    HardCase("alias_7x9", "close 7 x 9 board (half-turn symmetric) 0.55 m away, whole",
             _NARROW, _mount((0.03, -1.0, -0.1), 1.0, 25.0, 0.5),
             _board((7, 9), 0.06, (0.0, -0.8, 0.45)), whole_board_found=True, seed=15),
    HardCase("odd_even_7x10", "7 x 10 board (odd x even) 0.5 m away above the camera, 77-97 "
             "deg off the axis, 12 of its 54 inner corners cut by the top border",
             _WIDE, _mount((-0.02, -1.05, -0.1), -1.0, 32.0, -0.6),
             _board((7, 10), 0.05, (0.1, -1.6, 0.25)), seed=16),
    HardCase("even_even_8x6", "8 x 6 board on the ground 1.1-1.5 m away, its near row "
             "partly hidden by the bumper",
             _NARROW, _mount((0.0, -1.0, -0.1), 0.5, 35.0, 0.3),
             _board((8, 6), 0.09, (0.75, 0.0, 0.3), yaw=15.0, placement="ground"), seed=17),
)}


def hard_scene_dict(name: str, mount: dict | None = None) -> dict:
    """The scene file's content of case ``name``; the true mount unless ``mount``."""
    case = CASES[name]
    d = yaml.safe_load((SCENES / "vehicle_a.yaml").read_text())
    d["camera"] = {**copy.deepcopy(case.camera),
                   "mount": copy.deepcopy(case.mount if mount is None else mount)}
    d["test_site"] = {"objects": {k: {"enabled": False} for k in "ABCDEFG"},
                      "guidelines": {"enabled": False}, "board": copy.deepcopy(case.board)}
    return d


def moved(mount: dict, d_position_m: Sequence[float], d_ypr_deg: Sequence[float]) -> dict:
    """``mount`` moved by ``d_position_m`` (m) and turned by ``d_ypr_deg`` (degrees)."""
    m = copy.deepcopy(mount)
    m["position"] = [float(p + dp) for p, dp in zip(m["position"], d_position_m)]
    for key, dv in zip(("yaw_deg", "pitch_deg", "roll_deg"), d_ypr_deg):
        m[key] = float(m[key] + dv)
    return m


def hard_scene(name: str, d_position_m: Sequence[float] = (0.0, 0.0, 0.0),
               d_ypr_deg: Sequence[float] = (0.0, 0.0, 0.0)) -> Scene:
    """Case ``name``'s scene with its mount moved by ``d_position_m`` (m) and turned by
    ``d_ypr_deg`` (degrees) from the true mount."""
    return make_scene(hard_scene_dict(name, moved(CASES[name].mount, d_position_m, d_ypr_deg)))


@functools.lru_cache(maxsize=None)
def hard_truth(name: str) -> FisheyeImages:
    """Case ``name`` rendered at its true mount."""
    return render_fisheye(hard_scene(name))


@functools.lru_cache(maxsize=None)
def hard_capture(name: str) -> np.ndarray:
    """Case ``name``'s capture: the true frame degraded like a sensor, (H, W, 3) uint8."""
    truth = hard_truth(name)
    return degrade(truth.color, truth.labels, seed=CASES[name].seed)


def board_inner_corners(board: dict) -> np.ndarray:
    """The board's inner corners in the scene frame, (squares[0] − 1, squares[1] − 1, 3) m,
    index [i − 1, j − 1] for the corner after column i and row j.

    From the board's fields alone: an upright board stands facing the car (−Z), its width
    along +X turned by yaw about the vertical and its height up (−Y), the squares
    :data:`SQUARE_LIFT_M` in front of it; a ground board lies with its width along +X and
    its height along +Z (rearward), both turned by yaw, its squares at the plate's top.
    """
    nx, ny = board["squares"]
    s = board["square_size"]
    yaw = np.radians(board.get("yaw_deg", 0.0))
    along = np.array([np.cos(yaw), 0.0, -np.sin(yaw)])  # +X turned by yaw about +Y
    centre = np.asarray(board["position"], dtype=np.float64)
    if board["placement"] == "ground":
        up = np.array([np.sin(yaw), 0.0, np.cos(yaw)])  # +Z turned by the same yaw
        centre = centre * [1.0, 0.0, 1.0] + [0.0, -(GROUND_PLATE_M + SQUARE_LIFT_M), 0.0]
    else:
        up = np.array([0.0, -1.0, 0.0])
        facing = np.cross(along, up)  # toward the car: −Z at yaw 0
        centre = centre + SQUARE_LIFT_M * facing
    ii, jj = np.meshgrid(np.arange(1, nx) - nx / 2, np.arange(1, ny) - ny / 2, indexing="ij")
    return centre + s * (ii[..., None] * along + jj[..., None] * up)


@dataclass(frozen=True)
class CornerView:
    """A board's inner corners as a camera at some mount sees them.

    Attributes
    ----------
    uv : (N, 2) float64
        Pixels (u, v), corners in :func:`board_inner_corners`' order, flattened.
    off_axis_deg : (N,) float64
        Angle between each corner's ray and the optical axis, degrees.
    in_view : (N,) bool
        Inside the lens's field and inside the image (occlusion not checked).
    """

    uv: np.ndarray
    off_axis_deg: np.ndarray
    in_view: np.ndarray


def corner_view(name: str, mount: dict | None = None) -> CornerView:
    """Case ``name``'s inner corners seen from ``mount`` (default the true mount): by
    ``cv2.fisheye.projectPoints`` in front of the camera, and by the Kannala-Brandt formula
    written out here beyond 90° off its axis (where cv2's projection folds back); neither
    uses rvmsim's projection."""
    case = CASES[name]
    cam, m = case.camera, case.mount if mount is None else mount
    # camera-to-scene rotation Ry(yaw) · Rx(−pitch) · Rz(roll) (rvmsim.camera.mount)
    r_cs = Rotation.from_euler("YXZ", [m["yaw_deg"], -m["pitch_deg"], m["roll_deg"]],
                               degrees=True).as_matrix()
    pts = board_inner_corners(case.board).reshape(-1, 3)
    in_cam = (pts - np.asarray(m["position"])) @ r_cs
    intr, k = cam["intrinsics"], np.array(cam["lens"]["k"], dtype=np.float64)
    k_mat = np.array([[intr["fx"], 0, intr["cx"]], [0, intr["fy"], intr["cy"]], [0, 0, 1.0]])
    rho = np.hypot(in_cam[:, 0], in_cam[:, 1])
    theta = np.arctan2(rho, in_cam[:, 2])
    theta_d = theta * (1 + sum(kn * theta ** (2 * n + 2) for n, kn in enumerate(k)))
    uv = np.stack([intr["fx"] * theta_d * in_cam[:, 0] / rho + intr["cx"],
                   intr["fy"] * theta_d * in_cam[:, 1] / rho + intr["cy"]], axis=1)
    front = in_cam[:, 2] > 0
    cv_uv, _ = cv2.fisheye.projectPoints(in_cam[front].reshape(-1, 1, 3), np.zeros(3),
                                         np.zeros(3), k_mat, k.reshape(4, 1))
    uv[front] = cv_uv.reshape(-1, 2)
    w, h = cam["image_size"]
    off_axis = np.degrees(theta)
    in_view = ((off_axis <= cam["lens"]["fov_deg"] / 2)
               & (uv[:, 0] >= -0.5) & (uv[:, 0] <= w - 0.5)
               & (uv[:, 1] >= -0.5) & (uv[:, 1] <= h - 0.5))
    return CornerView(uv, off_axis, in_view)


def whole_board_detected(capture: np.ndarray, squares: tuple[int, int]) -> np.ndarray | None:
    """``cv2.findChessboardCornersSB``'s inner corners of a board of ``squares`` squares in
    the whole capture ((N, 2) px, flags EXHAUSTIVE | ACCURACY), or None when it finds none."""
    g = cv2.cvtColor(capture, cv2.COLOR_RGB2GRAY)
    ok, corners = cv2.findChessboardCornersSB(
        g, (squares[0] - 1, squares[1] - 1),
        flags=cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
    return corners.reshape(-1, 2) if ok else None
