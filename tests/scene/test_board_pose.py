"""The board's 6-DoF pose (placement: free), its colour convention, and minimal scenes
(no vehicle, no FMVSS site)."""

from __future__ import annotations

import copy
from pathlib import Path

import cv2
import numpy as np
import pytest

from rvmsim.errors import SceneError
from rvmsim.render import render_fisheye
from rvmsim.scene import (PatternBoard, build_parts, checker_corners, load_scene,
                          scene_from_dict, site_landmarks)
from rvmsim.scene.site import board_frame

from ..conftest import ROOT

BOARD_ONLY = ROOT / "docs" / "examples" / "board_only.yaml"


def _frame(**kw):
    return [np.asarray(v) for v in board_frame(PatternBoard(**kw))]


def test_free_board_with_zero_angles_is_the_upright_board():
    for got, want in zip(_frame(placement="free", yaw_deg=25.0),
                         _frame(placement="upright", yaw_deg=25.0)):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_free_board_pitched_90_has_the_ground_boards_axes():
    _, a, b, n = _frame(placement="free", pitch_deg=90.0, yaw_deg=-30.0)
    _, ga, gb, gn = _frame(placement="ground", yaw_deg=-30.0)
    for got, want in ((a, ga), (b, gb), (n, gn)):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_free_board_frame_is_right_handed_and_follows_roll():
    _, a, b, n = _frame(placement="free", yaw_deg=12.0, pitch_deg=-20.0, roll_deg=35.0)
    np.testing.assert_allclose(np.cross(a, b), n, atol=1e-12)
    _, a, b, _ = _frame(placement="free", roll_deg=10.0)
    assert a[1] > 0.1  # roll > 0 turns u toward −v (v is up, −Y; so u goes down, +Y)


@pytest.mark.parametrize("placement", ["ground", "upright"])
def test_pitch_or_roll_need_placement_free(placement, tmp_path):
    doc = (f"name: t\ncamera: {{image_size: [64, 48], intrinsics: {{fx: 20, fy: 20}}, "
           f"mount: {{position: [0, -1, 0]}}}}\n"
           f"test_site:\n  fmvss: false\n  board: {{placement: {placement}, pitch_deg: 10}}\n")
    (tmp_path / "s.yaml").write_text(doc)
    with pytest.raises(SceneError, match="placement: free"):
        load_scene(tmp_path / "s.yaml")


def test_minimal_scene_has_only_ground_and_board():
    scene = load_scene(BOARD_ONLY)
    assert scene.vehicle is None and not scene.test_site.fmvss
    names = {p.name for p in build_parts(scene)}
    assert names == {"ground", "pattern_board", "pattern_board_squares"}
    assert all(lm.name.startswith("board") for lm in site_landmarks(scene))


def test_fmvss_false_rejects_objects_and_guidelines(tmp_path):
    base = ("name: t\ncamera: {image_size: [64, 48], intrinsics: {fx: 20, fy: 20}, "
            "mount: {position: [0, -1, 0]}}\ntest_site:\n  fmvss: false\n")
    for extra in ("  objects: {A: {enabled: false}}\n", "  guidelines: {enabled: true}\n"):
        (tmp_path / "s.yaml").write_text(base + extra)
        with pytest.raises(SceneError, match="fmvss: false"):
            load_scene(tmp_path / "s.yaml")


def _board_only(pose: dict, squares=(8, 10)) -> dict:
    import yaml

    d = yaml.safe_load(BOARD_ONLY.read_text())
    d["test_site"]["board"] = {**d["test_site"]["board"], **pose, "squares": list(squares)}
    return d


def _detect(img: np.ndarray, squares) -> np.ndarray:
    grey = cv2.cvtColor(img, cv2.COLOR_RGB2GRAY)
    up = cv2.resize(grey, None, fx=2, fy=2, interpolation=cv2.INTER_CUBIC)
    ok, c = cv2.findChessboardCornersSB(up, (squares[0] - 1, squares[1] - 1),
                                        cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY)
    assert ok, "the chessboard detector did not find the rendered board"
    return (c.reshape(-1, 2) + 0.5) / 2 - 0.5


@pytest.mark.parametrize("pose", [
    {"placement": "free", "yaw_deg": 20.0, "pitch_deg": 15.0, "roll_deg": 10.0},
    {"placement": "free", "position": [-0.3, -0.7, 1.0], "yaw_deg": -35.0, "pitch_deg": 40.0,
     "roll_deg": -25.0},
])
def test_tilted_board_renders_where_cv2_projects_its_corners(pose):
    """The render's corners sit where cv2.fisheye.projectPoints puts checker_corners
    (≤ 0.5 px), and the colour convention holds (square (0, 0) black)."""
    scene = scene_from_dict(_board_only(pose), base_dir=BOARD_ONLY.parent)
    cam = scene.fisheye_camera()
    img = render_fisheye(scene).color
    corners = [c for c in checker_corners(scene) if c.name.startswith("board_inner")]
    pts = np.array([c.point for c in corners])
    rvec, tvec = cam.rvec_tvec
    proj = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K,
                                     cam.D)[0].reshape(-1, 2)
    found = _detect(img, scene.test_site.board.squares)
    # cv2's corner order is its own: match each projected corner to the nearest found one.
    d = np.linalg.norm(proj[:, None] - found[None], axis=2).min(axis=1)
    assert len(found) == len(proj) and np.percentile(d, 95) < 0.5 and d.max() < 0.8
    # Square (0, 0): the quarter-square beyond corner board_inner_1_1 along −a, −b is black.
    c11 = next(c for c in corners if c.name == "board_inner_1_1")
    s = scene.test_site.board.square_size
    centre_00 = np.asarray(c11.point) - 0.5 * s * (np.asarray(c11.axis_a) + np.asarray(c11.axis_b))
    centre_10 = centre_00 + s * np.asarray(c11.axis_a)
    uv = cv2.fisheye.projectPoints(np.array([centre_00, centre_10]).reshape(-1, 1, 3), rvec,
                                   tvec, cam.K, cam.D)[0].reshape(-1, 2)
    grey = img.mean(axis=2)
    (x0, y0), (x1, y1) = np.rint(uv).astype(int)
    assert grey[y0, x0] < 80 < 150 < grey[y1, x1]
    assert c11.black_ab  # black_ab of corner (1, 1) is the colour of square (1, 1): black


def test_board_size_is_honoured_by_mesh_and_corners():
    d = _board_only({"squares": [9, 7]}, squares=(9, 7))
    d["test_site"]["board"]["square_size"] = 0.05
    d["test_site"]["board"]["margin"] = 0.02
    scene = scene_from_dict(copy.deepcopy(d), base_dir=Path(BOARD_ONLY).parent)
    parts = {p.name: p for p in build_parts(scene)}
    assert len(parts["pattern_board_squares"].mesh.faces) == 2 * ((9 * 7 + 1) // 2)
    ext = parts["pattern_board"].mesh.vertices
    _, a, b, _ = board_frame(scene.test_site.board)
    span_a = np.ptp(ext @ a)
    span_b = np.ptp(ext @ b)
    assert span_a == pytest.approx(9 * 0.05 + 0.04) and span_b == pytest.approx(7 * 0.05 + 0.04)
    assert len([c for c in checker_corners(scene) if c.name.startswith("board")]) == 8 * 6


def test_tilted_board_only_scene_validates():
    """A capture of the tilted board, rendered from a camera 8 mm and 0.4° off the scene's,
    validates: the board's corners are matched and the pose correction is recovered."""
    from rvmsim.validate import validate

    d = _board_only({})
    true = copy.deepcopy(d)
    true["camera"]["mount"] = {"position": [0.008, -1.0, 0.0], "yaw_deg": 0.4}
    capture = render_fisheye(scene_from_dict(true, base_dir=BOARD_ONLY.parent)).color
    scene = scene_from_dict(d, base_dir=BOARD_ONLY.parent)
    res = validate(scene, capture, capture_name="tilted.png")
    assert res.n_inliers >= 40 and res.rms_after_px < 0.5 and res.passed
    corr = res.correction
    assert abs(corr.yaw_deg - 0.4) < 0.15 and abs(corr.d_position_mm[0] - 8.0) < 4.0


@pytest.mark.parametrize("rows", [10, 9])
def test_charuco_board_is_read_by_cv2_aruco_at_our_inner_corners(rows):
    """cv2.aruco.CharucoDetector finds every marker of the rendered ChArUco board, and its
    corner ids land on our board_inner corners (≤ 0.5 px) under the documented mapping."""
    cols = 7
    d = _board_only({"pattern": "charuco", "marker_size": 0.045, "yaw_deg": 10.0,
                     "pitch_deg": 5.0, "roll_deg": 5.0, "position": [0.0, -1.0, 1.0]},
                    squares=(cols, rows))
    d["camera"]["image_size"] = [960, 720]
    d["camera"]["intrinsics"] = {"fx": 300.0, "fy": 300.0}
    d["render"] = {"color_filter": "area"}  # the small markers alias under one bilinear tap
    scene = scene_from_dict(d, base_dir=BOARD_ONLY.parent)
    cam = scene.fisheye_camera()
    grey = cv2.cvtColor(render_fisheye(scene).color, cv2.COLOR_RGB2GRAY)
    up = cv2.resize(grey, None, fx=2, fy=2, interpolation=cv2.INTER_CUBIC)
    dic = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    board = cv2.aruco.CharucoBoard((cols, rows), 0.06, 0.045, dic)
    board.setLegacyPattern(rows % 2 == 0)
    corners, ids, _, marker_ids = cv2.aruco.CharucoDetector(board).detectBoard(up)
    assert marker_ids is not None and len(marker_ids) >= cols * rows // 2 - 1
    assert ids is not None and len(ids) >= 0.9 * (cols - 1) * (rows - 1)
    pts = {c.name: c.point for c in checker_corners(scene)}
    rvec, tvec = cam.rvec_tvec
    errs = []
    for k, p in zip(ids.ravel(), corners.reshape(-1, 2)):
        c, r = k % (cols - 1), k // (cols - 1)  # cv2's inner corner (c, r), r from the top
        point = np.array(pts[f"board_inner_{c + 1}_{rows - 1 - r}"])
        q = cv2.fisheye.projectPoints(point.reshape(1, 1, 3), rvec, tvec, cam.K, cam.D)[0]
        errs.append(np.linalg.norm((p + 0.5) / 2 - 0.5 - q.ravel()))
    assert np.median(errs) < 0.25 and max(errs) < 0.8


@pytest.mark.parametrize("board, match", [
    ({"pattern": "charuco"}, "marker_size"),
    ({"pattern": "charuco", "marker_size": 0.2}, "below square_size"),
    ({"pattern": "charuco", "marker_size": 0.03, "aruco_dictionary": "DICT_NOPE"},
     "not a cv2.aruco dictionary"),
    ({"pattern": "charuco", "marker_size": 0.03, "squares": [12, 12]}, "has 50 markers"),
    ({"marker_size": 0.03}, "for pattern: charuco"),
])
def test_charuco_settings_are_checked(board, match, tmp_path):
    d = _board_only({**board, "square_size": 0.05}, squares=tuple(board.get("squares", (8, 10))))
    import yaml

    (tmp_path / "s.yaml").write_text(yaml.safe_dump(d))
    with pytest.raises(SceneError, match=match):
        load_scene(tmp_path / "s.yaml")
