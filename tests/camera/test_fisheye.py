"""FisheyeCamera against OpenCV's independent cv2.fisheye implementation."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim.camera import Equidistance, FisheyeCamera, KannalaBrandt, rotation_from_ypr

KB = (-0.0185, 0.0041, -0.0029, 0.0003)


def _camera(k=(0.0, 0.0, 0.0, 0.0), skew=0.0, **kw) -> FisheyeCamera:
    args = dict(width=1280, height=960, fx=372.0, fy=379.5, cx=644.2, cy=476.8, k=k, skew=skew,
                fov_deg=192.0, rotation=rotation_from_ypr(1.5, 26.0, -0.7),
                position=np.array([0.05, -0.95, -0.12]))
    args.update(kw)
    return FisheyeCamera(**args)


def _points_in_front(cam: FisheyeCamera, n: int = 500, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    # Directions within 85° of the optical axis (cv2.fisheye's atan(r/z) needs z > 0).
    theta = np.radians(rng.uniform(0, 85, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    dist = rng.uniform(0.3, 20.0, n)
    d = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1)
    return cam.position + (d * dist[:, None]) @ cam.rotation.T


@pytest.mark.parametrize("k", [(0.0, 0.0, 0.0, 0.0), KB])
@pytest.mark.parametrize("skew", [0.0, 0.002])
def test_project_matches_cv2_fisheye(k, skew):
    cam = _camera(k=k, skew=skew)
    pts = _points_in_front(cam)
    rvec, tvec = cam.rvec_tvec
    ref, _ = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K, cam.D, alpha=skew)
    uv, in_fov = cam.project(pts)
    assert in_fov.all()
    np.testing.assert_allclose(uv, ref.reshape(-1, 2), atol=1e-6)


@pytest.mark.parametrize("k", [(0.0, 0.0, 0.0, 0.0), KB])
def test_pixel_rays_match_cv2_undistort(k):
    cam = _camera(k=k)
    rng = np.random.default_rng(1)
    uv = np.stack([rng.uniform(300, 980, 300), rng.uniform(200, 760, 300)], 1)
    rays, ok = cam.pixel_rays(uv)
    assert ok.all()
    und = cv2.fisheye.undistortPoints(uv.reshape(-1, 1, 2), cam.K, cam.D).reshape(-1, 2)
    np.testing.assert_allclose(rays[:, :2] / rays[:, 2:], und, atol=1e-6)


@pytest.mark.parametrize("k", [(0.0, 0.0, 0.0, 0.0), KB])
def test_round_trip_whole_image_including_beyond_90_degrees(k):
    cam = _camera(k=k)
    rays, ok = cam.image_rays()
    theta = np.degrees(np.arccos(np.clip(rays[..., 2], -1, 1)))
    assert theta[ok].max() > 93.0  # the test really covers rays behind the principal plane
    uv, in_fov = cam.project_rays(rays[ok])
    v, u = np.nonzero(ok)
    np.testing.assert_allclose(uv, np.stack([u, v], 1), atol=1e-6)
    assert in_fov.all()


def test_image_circle_matches_fov():
    cam = _camera()  # equidistance: image circle radius is f·fov/2 along each axis
    r_x = cam.fx * cam.theta_max
    rays, ok = cam.image_rays()
    row = int(round(cam.cy))
    cols = np.nonzero(ok[row])[0]
    assert abs((cols.max() - cam.cx) - r_x) <= 1.0
    assert abs((cam.cx - cols.min()) - r_x) <= 1.0


def test_scaled_camera_keeps_content_in_place():
    cam = _camera(k=KB)
    small = cam.scaled(0.25)
    pts = _points_in_front(cam, 50)
    uv, _ = cam.project(pts)
    uv_s, _ = small.project(pts)
    np.testing.assert_allclose(uv_s, (uv + 0.5) * 0.25 - 0.5, atol=1e-9)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(fx=0.0), "focal"),
        (dict(width=0), "image size"),
        (dict(k=(-0.5, 0.0, 0.0, 0.0)), "monotonic"),
        (dict(rotation=np.ones((3, 3))), "orthonormal"),
    ],
)
def test_invalid_camera(kw, match):
    with pytest.raises(ValueError, match=match):
        _camera(**kw)


def test_camera_is_frozen():
    cam = _camera()
    with pytest.raises(Exception):
        cam.fx = 1.0  # type: ignore[misc]
    with pytest.raises(ValueError):
        cam.rotation[0, 0] = 2.0


def test_the_lens_model_is_named_not_read_from_k():
    """``lens_model`` chooses the lens; k = 0 does not turn a Kannala-Brandt camera into
    an equidistance one, and an equidistance camera refuses coefficients."""
    assert _camera(lens_model="equidistance").lens == Equidistance()
    assert _camera().lens == KannalaBrandt((0.0, 0.0, 0.0, 0.0))
    assert _camera(k=KB).lens == KannalaBrandt(KB)
    with pytest.raises(ValueError, match="takes no k"):
        _camera(k=KB, lens_model="equidistance")
    with pytest.raises(ValueError, match="unknown lens model"):
        _camera(lens_model="fish")
