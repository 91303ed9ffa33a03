"""cv2.fisheye.calibrate on rendered board views: the intrinsics and the lens radius come
back, and a bad view is rejected."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvmsim.calibrate import calibrate_fisheye
from rvmsim.errors import RvmsimError

from .conftest import board_pose, board_scene, POSES


def _truth():
    return board_scene(board_pose(*POSES[0])).fisheye_camera()


def check_recovered(K: np.ndarray, D: np.ndarray) -> None:
    """fx, fy, cx, cy within 0.3 %, the lens radius fx·θd(θ) within 0.5 px up to 80°."""
    cam = _truth()
    for (i, j) in ((0, 0), (1, 1), (0, 2), (1, 2)):
        assert K[i, j] == pytest.approx(cam.K[i, j], rel=0.003), (i, j)
    th = np.radians(np.linspace(0.0, 80.0, 161))

    def radius(f, d):
        return f * th * (1 + d[0] * th**2 + d[1] * th**4 + d[2] * th**6 + d[3] * th**8)

    err = np.abs(radius(K[0, 0], np.ravel(D)) - radius(cam.K[0, 0], np.ravel(cam.D)))
    assert err.max() < 0.5


def test_calibration_recovers_the_rendered_camera(detected_views):
    board, views = detected_views
    assert len(views) >= 10
    calib = calibrate_fisheye(views, board, (640, 480))
    check_recovered(calib.K, calib.D)
    assert all(v.used for v in calib.views) and calib.rms_px < 0.5


def test_a_bad_view_is_rejected_and_the_rest_still_calibrates(detected_views):
    board, views = detected_views
    rng = np.random.default_rng(3)
    bad = dataclasses.replace(views[4], name="bad",
                              corners=views[4].corners + rng.normal(0, 4.0, views[4].corners.shape))
    calib = calibrate_fisheye([*views[:4], bad, *views[5:]], board, (640, 480))
    used = {v.name: v.used for v in calib.views}
    assert used["bad"] is False and sum(used.values()) == len(views) - 1
    check_recovered(calib.K, calib.D)


def test_too_few_views_is_an_error(detected_views):
    board, views = detected_views
    with pytest.raises(RvmsimError, match="at least 3"):
        calibrate_fisheye(views[:2], board, (640, 480))
