"""rvmsim.pose.fit: the pose fit, the dense pre-alignment and the checker-shift
disambiguation, on perturbed synthetic captures and on the real frame."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.camera import rotation_from_ypr
from rvmsim.scene import pattern_shade
from rvmsim.pose import fit_pose
from rvmsim.validate import ValidationSettings, validate
from rvmsim.pose.landmarks import visible_landmarks
from rvmsim.pose.fit import GroundShade, dense_align
from rvmsim.pose.projection import corrected_pose, project

from rvmsim.testing.captures import (BAIC, D_POS_MM, D_YPR_DEG, MOUNT, baic, baic_rough_scene,
                                     base, perturbed, perturbed_validation, wrong_scene)
from ..conftest import needs_real


def test_fit_pose_recovers_an_exact_correction():
    """Corners projected exactly at a known corrected pose: the fit from zero returns that
    correction (≤ 1e-6 m, 1e-5°) with ~zero residuals."""
    sc, syn = base()
    cam = syn.camera
    m = sc.camera.mount
    ypr0 = np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    lm = visible_landmarks(sc, syn, 8)
    pts = lm.points[lm.usable]
    x_true = np.array([0.006, -0.004, 0.008, 0.8, -0.7, 0.5])
    uv = project(cam, *corrected_pose(cam, ypr0, x_true), pts)
    x, resid, sigma = fit_pose(cam, ypr0, pts, uv, robust=False)
    np.testing.assert_allclose(x[:3], x_true[:3], atol=1e-6)
    np.testing.assert_allclose(x[3:], x_true[3:], atol=1e-5)
    assert resid.max() < 1e-4 and sigma.shape == (6,)


def test_pattern_shade_matches_rendered_mat():
    """The analytic mat layout (used to tell checker shifts apart) is what the renderer draws:
    pixel rays hit the ground where pattern_shade says black or white, and the rendered
    colour agrees on ≥ 99 % of the mat's pixels away from the square borders."""
    sc, syn = base()
    cam = syn.camera
    mat = syn.labels == L.GROUND_PATTERN
    vv, uu = np.nonzero(mat)
    rays, _ = cam.pixel_rays(np.stack([uu, vv], axis=1).astype(float))
    d = rays @ cam.rotation.T
    t = (-0.004 - cam.position[1]) / d[:, 1]
    x, z = cam.position[0] + t * d[:, 0], cam.position[2] + t * d[:, 2]
    shade = pattern_shade(sc.test_site.ground_patterns[0], x, z)
    grey = cv2.cvtColor(syn.color, cv2.COLOR_RGB2GRAY)[vv, uu]
    # Stay 2 px clear of any black/white border (sampled shade differs at distance).
    border = cv2.dilate(cv2.Canny(cv2.cvtColor(syn.color, cv2.COLOR_RGB2GRAY), 50, 150),
                        np.ones((5, 5), np.uint8))[vv, uu] == 0
    assert np.isfinite(shade[border]).mean() > 0.99
    agree = (grey[border] > 128) == (shade[border] > 0.5)
    assert agree.mean() > 0.99, agree.mean()


def test_dense_alignment_moves_towards_the_capture_pose():
    """On the perturbed capture the shade correlation is higher at the true pose than at
    the scene's, and the Nelder-Mead pre-alignment raises it and moves the angles towards
    the true error."""
    sc, syn = base()
    _, cap = perturbed()
    cam = syn.camera
    m = sc.camera.mount
    ypr0 = np.array([m.yaw_deg, m.pitch_deg, m.roll_deg])
    shade = GroundShade.sample(sc, cam, syn.labels, cap)
    x_true = np.array([*(v / 1000 for v in D_POS_MM), *D_YPR_DEG])
    at_scene = shade(*corrected_pose(cam, ypr0, np.zeros(6)))
    assert shade(*corrected_pose(cam, ypr0, x_true)) > at_scene
    x = dense_align(shade, cam, ypr0)
    assert shade(*corrected_pose(cam, ypr0, x)) > at_scene
    assert np.linalg.norm(x[3:] - x_true[3:]) < np.linalg.norm(x_true[3:])
    assert len(shade.shifts()) == 12  # same-polarity (du, dv) up to two squares, not (0, 0)


def test_perturbed_capture_recovers_the_pose_error():
    res, tampered = perturbed_validation()
    c = res.correction
    for got, want in zip(c.d_position_mm, D_POS_MM):
        assert abs(got - want) <= 10.0, (c.d_position_mm, D_POS_MM)
    for got, want in zip((c.d_yaw_deg, c.d_pitch_deg, c.d_roll_deg), D_YPR_DEG):
        assert abs(got - want) <= 0.2, (got, want)
    assert res.rms_after_px <= 0.5
    assert res.rms_before_px > 3.0  # the error was there to find
    assert res.n_inliers >= 30
    # The moved corners are not among the inliers.
    by_name = {m.name: m for m in res.landmarks}
    assert all(not by_name[n].inlier for n in tampered if n in by_name)
    # The 0.8° yaw error fails the default 0.5° tolerance and says what to do.
    failed = [k for k in res.checks if not k.passed]
    assert [k.name for k in failed] == ["pose_angle_correction_deg"]
    assert "--write-scene" in failed[0].hint
    # After the correction the edges line up better than before.
    assert res.edges_after is not None
    assert res.edges_after.chamfer_px < res.edges_before.chamfer_px


def test_pose_fit_agrees_with_cv2_fisheye_solvepnp():
    """Our fit (in the scene's mount parameters) and OpenCV's fisheye PnP on the same
    inliers give the same camera pose."""
    res, _ = perturbed_validation()
    inl = [m for m in res.landmarks if m.inlier]
    pts = np.array([m.point for m in inl])
    uv = np.array([m.found_px for m in inl])
    sc, syn = base()
    cam = syn.camera
    ok, rvec, tvec = cv2.fisheye.solvePnP(pts.reshape(-1, 1, 3), uv.reshape(-1, 1, 2),
                                          cam.K, cam.D, flags=cv2.SOLVEPNP_ITERATIVE)
    assert ok
    r_sc, _ = cv2.Rodrigues(rvec)
    pos_cv = -r_sc.T @ tvec.ravel()
    c = res.correction
    rot = rotation_from_ypr(c.yaw_deg, c.pitch_deg, c.roll_deg)
    angle = math.degrees(np.arccos(np.clip((np.trace(rot.T @ r_sc.T) - 1) / 2, -1, 1)))
    assert angle < 0.05, angle  # cv2 minimises the error on the undistorted plane, we in px
    assert np.linalg.norm(pos_cv - np.array(c.position_m)) * 1000 < 2.0


def test_grossly_wrong_pose_fails_the_verdict():
    """A scene whose camera sits 60 mm lower and 3° off in pitch than the capture's."""
    _, cap = perturbed()
    res = validate(wrong_scene(), cap, ValidationSettings(rerender=False))
    assert not res.passed
    names = {k.name for k in res.checks if not k.passed}
    assert names == {"pose_position_correction_mm", "pose_angle_correction_deg"}
    assert res.correction.d_pitch_deg == pytest.approx(-3.7, abs=0.2)
    assert res.correction.d_position_mm[1] == pytest.approx(-64.0, abs=10.0)
    assert res.rms_after_px < 0.5
    assert MOUNT["pitch_deg"] + D_YPR_DEG[1] == pytest.approx(res.correction.pitch_deg, abs=0.2)


@needs_real
@pytest.mark.slow  # test_global_search.py runs the rough start
def test_real_capture_from_the_rough_pose_finds_the_same_pose():
    """Starting from the capture README's rough pose (0.97 m, 38°, no yaw or roll, centred)
    the search lands on the bundled scene's pose: the periodic checker does not fool it."""
    sc, cap, syn = baic()
    res = validate(baic_rough_scene(sc), cap, ValidationSettings(rerender=False),
                   capture_name=str(BAIC))
    m = sc.camera.mount
    c = res.correction
    assert res.rms_after_px <= 2.0 and res.n_inliers >= 35
    assert np.linalg.norm(np.subtract(c.position_m, m.position)) < 0.01
    assert abs(c.yaw_deg - m.yaw_deg) < 0.1
    assert abs(c.pitch_deg - m.pitch_deg) < 0.1
    assert abs(c.roll_deg - m.roll_deg) < 0.1
    assert res.rms_before_px > 5.0 and not res.passed
