"""rvmsim.pose.landmarks: which checker corners the synthetic frame shows usably."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.scene import checker_corners
from rvmsim.pose.landmarks import spacing_px, usable_corners, visible_landmarks

from rvmsim.testing.captures import base, make_scene, scene_dict


def test_checker_corners_project_like_cv2_and_lie_on_rendered_saddles():
    """Every visible checker corner projects with our lens model as cv2.fisheye.projectPoints
    projects it (≤ 0.01 px), and the rendered frame has its saddle point there: cornerSubPix
    started 2 px off comes back within 0.6 px."""
    sc, syn = base()
    cam = syn.camera
    corners = checker_corners(sc)
    pts = np.array([c.point for c in corners])
    ours, _ = cam.project(pts)
    rvec, tvec = cam.rvec_tvec
    theirs, _ = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K, cam.D)
    front = cam.scene_to_camera(pts)[:, 2] > 0.05  # cv2's model stops at 90° off-axis
    assert front.sum() >= 60
    np.testing.assert_allclose(ours[front], theirs.reshape(-1, 2)[front], atol=0.01)
    spacing = spacing_px(cam, cam.position, cam.rotation, corners)
    usable = usable_corners(cam, corners, syn.labels, ours, spacing)
    assert usable.sum() >= 30 and front[usable].all()
    grey = cv2.cvtColor(syn.color, cv2.COLOR_RGB2GRAY).astype(np.float32)
    errs = []
    for n in np.flatnonzero(usable):
        start = (ours[n] + [2.0, -1.5]).astype(np.float32).reshape(1, 1, 2)
        w = int(np.clip(round(0.3 * spacing[n]), 3, 12))
        p = cv2.cornerSubPix(grey, start, (w, w), (-1, -1),
                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
        errs.append(np.linalg.norm(p.ravel() - ours[n]))
    assert max(errs) < 0.6, max(errs)


def test_visible_landmarks_are_the_usable_corners_at_the_scene_pose():
    sc, syn = base()
    lm = visible_landmarks(sc, syn, 8)
    cam = syn.camera
    ours, _ = cam.project(lm.points)
    np.testing.assert_allclose(lm.predicted_px, ours, atol=1e-9)
    assert lm.n_usable == int(lm.usable.sum()) and 30 <= lm.n_usable < len(lm.corners)
    with pytest.raises(RvmsimError, match=f"only {lm.n_usable} checker corners are visible"):
        visible_landmarks(sc, syn, lm.n_usable + 1)


def test_a_scene_without_checkers_has_no_landmarks():
    _, syn = base()
    d = scene_dict()
    d["test_site"] = {"board": {"enabled": False}}
    with pytest.raises(RvmsimError, match="the scene has no checker landmarks"):
        visible_landmarks(make_scene(d), syn, 8)
