"""ChArUco boards in the validation: found by their markers (cv2.aruco), as the start and
as the board's landmarks, and scored by colour around the markers."""

from __future__ import annotations

import copy
import functools

import cv2
import numpy as np
import pytest
import yaml

from rvmsim.render import render_fisheye
from rvmsim.scene import Scene, checker_corners, scene_from_dict
from rvmsim.pose import BoardShade, board_layout
from rvmsim.validate import ValidationSettings, validate
from rvmsim.pose.capture import grey
from rvmsim.pose.charuco import detect_charuco

from ..conftest import ROOT
from rvmsim.testing.captures import degrade

BOARD_ONLY = ROOT / "docs" / "examples" / "board_only.yaml"
#: 7 × 10 squares of 0.08 m with 0.06 m markers (10 rows: cv2's legacy square order), 1 m
#: from the camera: about 3 px per marker cell once degraded (at 2 px most markers are lost).
CHARUCO = {"pattern": "charuco", "marker_size": 0.06, "squares": [7, 10],
           "square_size": 0.08, "position": [0.1, -1.05, 1.0]}


def _scene(d_position_m=(0.0, 0.0, 0.0), d_ypr_deg=(0.0, 0.0, 0.0), board=CHARUCO) -> Scene:
    """The bundled board-only example with a ChArUco board, 960 × 720; the mount moved."""
    d = yaml.safe_load(BOARD_ONLY.read_text())
    d["test_site"]["board"].update(copy.deepcopy(board))
    d["camera"]["image_size"] = [960, 720]
    d["camera"]["intrinsics"] = {"fx": 300.0, "fy": 300.0}
    m = d["camera"]["mount"]
    m["position"] = [p + dp for p, dp in zip(m["position"], d_position_m)]
    for key, dv in zip(("yaw_deg", "pitch_deg", "roll_deg"), d_ypr_deg):
        m[key] = m.get(key, 0.0) + dv
    return scene_from_dict(d, base_dir=BOARD_ONLY.parent)


@functools.lru_cache(maxsize=None)
def _capture() -> np.ndarray:
    truth = render_fisheye(_scene())
    return degrade(truth.color, truth.labels, seed=5)


def test_detected_corners_are_our_inner_corners():
    """detect_charuco's (i, j) land on the scene's inner corners, projected independently
    by cv2.fisheye.projectPoints: median ≤ 0.2 px, all ≤ 0.6 px, most of the 54 found."""
    scene = _scene()
    cam = scene.fisheye_camera()
    layout = board_layout(scene, tuple(checker_corners(scene)))
    assert layout is not None and layout.charuco is not None
    det = detect_charuco(np.clip(grey(_capture()), 0, 255).astype(np.uint8), layout.charuco)
    assert det is not None
    ij, px = det
    assert len(ij) >= 40
    rvec, tvec = cam.rvec_tvec
    pts = layout.corner_points[ij[:, 0], ij[:, 1]]
    want = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K, cam.D)[0]
    err = np.linalg.norm(px - want.reshape(-1, 2), axis=1)
    assert np.median(err) <= 0.2 and err.max() <= 0.6, (np.median(err), err.max())


@pytest.mark.parametrize("d_pos, d_ypr", [((0.3, -0.3, 0.3), (10.0, -10.0, 10.0)),
                                          pytest.param((-0.3, 0.3, -0.3), (-10.0, 10.0, -10.0),
                                                       marks=pytest.mark.slow)])
def test_from_10_degrees_and_30_cm_off_its_markers_give_the_pose(d_pos, d_ypr):
    res = validate(_scene(d_pos, d_ypr), _capture(), ValidationSettings(rerender=False))
    assert res.start.startswith("the board found by its ChArUco markers"), res.start
    truth = _scene().camera.mount
    c = res.correction
    d_mm = (np.array(c.position_m) - np.array(truth.position)) * 1000
    d_deg = np.array([c.yaw_deg - truth.yaw_deg, c.pitch_deg - truth.pitch_deg,
                      c.roll_deg - truth.roll_deg])
    assert np.all(np.abs(d_mm) <= 2.0), d_mm
    assert np.all(np.abs(d_deg) <= 0.05), d_deg
    assert res.n_inliers >= 48
    methods = [m.method for m in res.landmarks if m.found_px is not None]
    assert set(methods) <= {"charuco", "local"} and methods.count("charuco") >= 40, methods


def test_the_colour_score_looks_around_the_markers():
    """At the true pose the squares' colours fit (the white squares sampled in the ring
    around their markers); one square off diagonally they do not."""
    scene = _scene()
    cam = scene.fisheye_camera()
    layout = board_layout(scene, tuple(checker_corners(scene)))
    shade = BoardShade(layout, cam, grey(_capture()).astype(np.float32))
    true_score = shade(cam.position, cam.rotation)
    assert true_score > 0.9
    s = layout.square_size
    assert shade(cam.position + s * (layout.a + layout.b), cam.rotation) < true_score - 0.15
    # sampled at the square centres instead, the markers would spoil the white squares
    plain = board_layout(_scene(board={**CHARUCO, "pattern": "checker", "marker_size": None}),
                         tuple(checker_corners(scene)))
    assert plain is not None
    assert BoardShade(plain, cam, grey(_capture()).astype(np.float32))(
        cam.position, cam.rotation) < true_score - 0.1
