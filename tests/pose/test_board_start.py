"""rvmsim.pose.board_start and .board: the global start from the board the chessboard
detector finds, and the one-square alias."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.camera import rotation_from_ypr
from rvmsim.render import render_fisheye
from rvmsim.scene import checker_corners
from rvmsim.pose import BoardShade, board_layout, find_board_start
from rvmsim.validate import ValidationSettings, validate
from rvmsim.camera import ypr_from_rotation
from rvmsim.pose.capture import grey
from rvmsim.pose.landmarks import visible_landmarks
from rvmsim.pose.fit import PoseSearch, find_pose

from rvmsim.testing.captures import (BOARD_MOUNT, BOARD_SQUARE_M, MOUNT, board_capture,
                                     board_scene, base, make_scene, moved_mount, perturbed,
                                     perturbed_mount, scene_dict)


def _pose_error(res, mount: dict) -> tuple[np.ndarray, np.ndarray]:
    """(position mm, yaw/pitch/roll degrees) of the corrected mount minus ``mount``."""
    c = res.correction
    d_pos = (np.array(c.position_m) - np.array(mount["position"])) * 1000
    d_ang = np.array([c.yaw_deg - mount["yaw_deg"], c.pitch_deg - mount["pitch_deg"],
                      c.roll_deg - mount["roll_deg"]])
    return d_pos, d_ang


def test_ypr_from_rotation_inverts_rotation_from_ypr():
    rng = np.random.default_rng(0)
    for _ in range(20):
        ypr = rng.uniform([-170, -80, -170], [170, 80, 170])
        np.testing.assert_allclose(ypr_from_rotation(rotation_from_ypr(*ypr)), ypr, atol=1e-9)


@pytest.mark.parametrize("d_pos, d_ypr", [((0.3, -0.3, 0.3), (10.0, -10.0, 10.0)),
                                          pytest.param((-0.3, 0.3, -0.3), (-10.0, 10.0, -10.0),
                                                       marks=pytest.mark.slow)])
def test_starts_off_by_10_degrees_and_30_cm_converge_to_the_true_pose(d_pos, d_ypr):
    """The capture is the test scene's own render at :data:`MOUNT` (so the truth is known
    to the renderer's ~0.2 px); the scene starts ±10° and ±0.3 m off on every axis.  The
    board's 12 corners 2.9 m away do not pin the pose (a flipped pose fits them about as
    well), so the mat's shade gives the start, or where the fit from it fails, the
    board's."""
    capture = base()[1].color
    scene = make_scene(scene_dict(moved_mount(d_pos, d_ypr)))
    m = scene.camera.mount
    board = find_board_start(capture, scene.fisheye_camera(),
                             np.array([m.yaw_deg, m.pitch_deg, m.roll_deg]),
                             board_layout(scene, tuple(checker_corners(scene))))
    assert board is None or not board.pins_pose
    res = validate(scene, capture, ValidationSettings(rerender=False))
    assert res.start.startswith(("the pose whose patterns' shade",
                                 "the board found by the chessboard detector")), res.start
    d_mm, d_deg = _pose_error(res, MOUNT)
    assert np.all(np.abs(d_mm) <= 2.0), d_mm
    assert np.all(np.abs(d_deg) <= 0.05), d_deg
    assert res.n_inliers >= 30


def test_degraded_capture_from_10_degrees_off_finds_its_pose():
    """The perturbed, sensor-degraded capture (other textures, exposure, blur, noise), from
    a scene 10° / 0.3 m off: its true pose within the renderer's floor."""
    truth, capture = perturbed()
    far = validate(make_scene(scene_dict(moved_mount((0.3, 0.3, -0.3), (-10.0, -10.0, 10.0)))),
                   capture, ValidationSettings(rerender=False))
    np.testing.assert_allclose(far.correction.position_m, truth.camera.position, atol=3e-3)
    tm = perturbed_mount()
    np.testing.assert_allclose([far.correction.yaw_deg, far.correction.pitch_deg,
                                far.correction.roll_deg],
                               [tm["yaw_deg"], tm["pitch_deg"], tm["roll_deg"]], atol=0.06)


def test_without_the_global_start_such_a_pose_is_a_detection_failure():
    """Neither the board start nor the mat's shade search (``dense_align=False``; with it,
    the mat alone finds this pose: tests/validate/test_global_search.py)."""
    from rvmsim.pose import PoseFailure

    scene = make_scene(scene_dict(moved_mount((0.3, -0.3, 0.3), (10.0, -10.0, 10.0))))
    with pytest.raises(PoseFailure) as err:
        validate(scene, base()[1].color,
                 ValidationSettings(rerender=False, global_start=False, dense_align=False))
    assert err.value.step == "detection" and "(step failed: detection)" in str(err.value)
    assert {"overlay", "edges", "landmarks"} <= set(err.value.images)
    assert "--search-px" not in str(err.value)


@pytest.mark.parametrize("views", [("whole image",), ("perspective view",)])
def test_board_start_finds_the_board_from_far_off(views):
    """In the whole capture and in a perspective view around the predicted direction."""
    cap = board_capture()
    d = np.array([8.0, -6.0, 9.0])
    scene = board_scene((0.15, -0.1, 0.2), d_ypr_deg=tuple(d))
    cam = scene.fisheye_camera()
    m = scene.camera.mount
    ypr0 = np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    start = find_board_start(cap, cam, ypr0, board_layout(scene, tuple(checker_corners(scene))),
                             views=views)
    assert start is not None and start.view == views[0] and start.rms_px < 0.5
    assert start.ambiguous  # 7 × 9 squares: half-turn symmetric, the CAD pose chose
    np.testing.assert_allclose(cam.position + start.x[:3], BOARD_MOUNT["position"], atol=0.006)
    truth = [BOARD_MOUNT["yaw_deg"], BOARD_MOUNT["pitch_deg"], BOARD_MOUNT["roll_deg"]]
    np.testing.assert_allclose(ypr0 + start.x[3:], truth, atol=0.3)


def test_board_orientation_comes_from_its_colours():
    """5 × 4 squares: a half turn swaps the colours, so the board's orientation is defined,
    even from a scene pose turned 10° the other way."""
    scene = make_scene(scene_dict(moved_mount((0.2, 0.1, -0.2), (-8.0, 6.0, 9.0))))
    m = scene.camera.mount
    ypr0 = np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    start = find_board_start(base()[1].color, scene.fisheye_camera(), ypr0,
                             board_layout(scene, tuple(checker_corners(scene))))
    assert start is not None and not start.ambiguous and start.colour_score > 0.8
    truth = [MOUNT["yaw_deg"], MOUNT["pitch_deg"], MOUNT["roll_deg"]]
    # a half turn would be 180° off; the start itself (a PnP on the detected corners, refined
    # afterwards) is within a few degrees (3.06° in yaw seen on a fresh render)
    assert np.all(np.abs(ypr0 + start.x[3:] - truth) < 5.0)


def test_one_square_diagonal_alias_is_corrected_not_accepted():
    """A board-only scene whose pose is one square off diagonally: every inner corner the
    alias predicts has the right colour order.  The board start (detector + PnP) and, without
    it, the board's square colours (:class:`BoardShade`) both correct it."""
    s = BOARD_SQUARE_M
    off = board_scene((s, -s, 0.0))  # the camera one square along a and b (b is up)
    for global_start in (True, False):
        res = validate(off, board_capture(),
                       ValidationSettings(rerender=False, global_start=global_start))
        d_mm, d_deg = _pose_error(res, BOARD_MOUNT)
        assert np.all(np.abs(d_mm) <= 3.0), (global_start, d_mm)
        assert np.all(np.abs(d_deg) <= 0.1), (global_start, d_deg)
        assert res.n_inliers == 48
        # 7 × 9 squares: half-turn symmetric, the CAD pose chose (and says so).
        assert ("half-turn symmetric" in res.start) == global_start


def _board_search(scene, name: str):
    """(the PoseSearch of the board capture from ``scene``'s pose, its frame, landmarks)."""
    syn = render_fisheye(scene)
    lm = visible_landmarks(scene, syn, 8)
    m = scene.camera.mount
    search = PoseSearch(board_capture(), syn, scene, lm,
                        np.array([m.yaw_deg, m.pitch_deg, m.roll_deg]), 30.0, 8, name)
    return search, syn, lm


def test_without_the_board_colours_the_alias_would_be_accepted():
    """The alias is real: matching and fitting alone lock onto it; the board shade does not."""
    s = BOARD_SQUARE_M
    off = board_scene((s, -s, 0.0))
    search, syn, lm = _board_search(off, "alias")
    cap = board_capture()
    alias = find_pose(search)
    assert np.linalg.norm(alias.x[:3]) < 0.01  # stays one square (113 mm) off the truth
    layout = board_layout(off, lm.corners)
    shade = BoardShade(layout, syn.camera, grey(cap).astype(np.float32))
    fixed = find_pose(search, shade, layout.corner_index.ravel())
    np.testing.assert_allclose(fixed.x[:3], [-s, s, 0.0], atol=0.004)
    assert shade(*search.pose(fixed.x)) > shade(*search.pose(alias.x)) + 0.1


def _exact_start(det_ij: np.ndarray, scene):
    """:func:`_best_start` from ``scene``'s pose on a 'detection' that is the exact
    projections, at the true pose (:data:`MOUNT`), of the board's lattice points ``det_ij``
    (rows, cols, 2)."""
    from rvmsim.pose.board_start import _best_start
    from rvmsim.pose.projection import project

    truth = base()[0].fisheye_camera()
    layout = board_layout(scene, tuple(checker_corners(scene)))
    s = layout.square_size
    pts = (layout.origin + det_ij[..., :1] * s * layout.a + det_ij[..., 1:] * s * layout.b)
    det = project(truth, truth.position, truth.rotation, pts.reshape(-1, 3)).reshape(
        *det_ij.shape[:2], 2)
    cam = scene.fisheye_camera()
    m = scene.camera.mount
    ypr0 = np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    shade = BoardShade(layout, cam, grey(base()[1].color).astype(np.float32))
    start = _best_start(cam, ypr0, layout, det, shade, "test")
    return start, ypr0


@pytest.mark.parametrize("flip_rows, flip_cols", [(1, 1), (-1, 1), (1, -1), (-1, -1)])
def test_a_grid_that_takes_the_boards_edge_for_a_row_is_read_right(flip_rows, flip_cols):
    """The detector's grid on a small blurred 5 × 4 board (4 × 3 inner corners) was once
    3 × 4: three of the inner columns turned a quarter, and the board's lower edge as a
    fourth row.  Read as the board's own grid that is a pose 90° off with RMS 0.27 px; read
    as a patch of the board's lattice it is the true pose, from a scene 8° and 0.2 m off."""
    scene = make_scene(scene_dict(moved_mount((0.2, 0.1, -0.2), (-8.0, 6.0, 5.0))))
    r, c = np.mgrid[0:3, 0:4]
    det_ij = np.stack([3 - r, 2 - c], axis=-1)[::flip_rows, ::flip_cols]  # i = 1..3, j = -1..2
    start, ypr0 = _exact_start(det_ij, scene)
    assert start is not None and not start.ambiguous
    cam = scene.fisheye_camera()
    np.testing.assert_allclose(cam.position + start.x[:3], MOUNT["position"], atol=1e-3)
    np.testing.assert_allclose(ypr0 + start.x[3:],
                               [MOUNT["yaw_deg"], MOUNT["pitch_deg"], MOUNT["roll_deg"]],
                               atol=0.01)
    # only the nine inner corners are the start's corners; the edge row is not one
    assert sorted(map(tuple, start.corner_ij)) == [(i, j) for i in (1, 2, 3) for j in (0, 1, 2)]
    assert start.colour_score > 0.9


def test_a_start_turned_far_from_the_scenes_rotation_is_not_believed():
    """The whole inner grid, exact; from a scene 10° off in yaw it gives the true pose, from
    one 40° off none: no CAD mount is that far from the real one."""
    r, c = np.mgrid[0:3, 0:4]
    det_ij = np.stack([c, r], axis=-1)
    near, _ = _exact_start(det_ij, make_scene(scene_dict(moved_mount((0, 0, 0), (10, 0, 0)))))
    assert near is not None and abs(near.x[3] + 10.0) < 0.01
    far, _ = _exact_start(det_ij, make_scene(scene_dict(moved_mount((0, 0, 0), (40, 0, 0)))))
    assert far is None


def test_corners_matched_on_squares_of_the_wrong_colours_are_refused():
    """Step ``correspondence``: the board's corners match, but at the fitted pose its
    squares' colours do not explain the capture the shade looks at (here the board's area
    painted over with noise), and no same-colour shift does better: the fit is refused, not
    accepted, with what was found."""
    from rvmsim import labels as L
    from rvmsim.pose import PoseFailure

    scene = board_scene()
    search, syn, lm = _board_search(scene, "painted")
    cap = board_capture()
    layout = board_layout(scene, lm.corners)
    assert find_pose(search, BoardShade(layout, syn.camera, grey(cap).astype(np.float32)),
                     layout.corner_index.ravel()).inliers.sum() >= 40  # the true board: fine
    painted = grey(cap).astype(np.float32)
    board = syn.labels == L.BOARD
    painted[board] = np.random.default_rng(1).uniform(0, 255, int(board.sum()))
    with pytest.raises(PoseFailure) as err:
        find_pose(search, BoardShade(layout, syn.camera, painted), layout.corner_index.ravel())
    assert err.value.step == "correspondence" and "one square off" in str(err.value)
    assert err.value.found is not None and np.isfinite(err.value.found[:, 0]).sum() >= 30


def test_a_board_found_only_far_from_the_scenes_pose_is_a_detection_failure_saying_so():
    """The scene's camera turned 120° away from its board, and the capture is of the board:
    the detector finds the board, but only a pose 120° from the scene's explains it (no CAD
    mount is that far off), and the scene's view has no corners.  It is a ``detection``
    failure naming that cause, with the pictures (the board's corners drawn), not a bare
    error."""
    from rvmsim.pose import PoseFailure

    scene = board_scene(d_ypr_deg=(120.0, 0.0, 0.0))
    with pytest.raises(PoseFailure) as err:
        validate(scene, board_capture(), ValidationSettings(rerender=False))
    assert err.value.step == "detection"
    msg = str(err.value)
    # 120° from the scene's, or its 180° twin: the 8 × 12 board's colours are symmetric
    # under a half turn, and which twin the detector's corner order gives depends on the
    # OpenCV build (5.1.0.95 gives 180°)
    import re

    found = re.search(r"a pose (\d+)° and", msg)
    assert "the board was found (48 corners" in msg and found, msg
    assert int(found.group(1)) in (120, 180), msg
    assert "is the scene's mount right?" in msg
    assert "checker corners are visible" in msg
    assert {"overlay", "edges", "landmarks", "board"} <= set(err.value.images)
    # the board picture marks the detector's corners on the capture (yellow circles)
    diff = np.any(err.value.images["board"] != board_capture(), axis=-1)
    assert diff.sum() > 48 * 8
