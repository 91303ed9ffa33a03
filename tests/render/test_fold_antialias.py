"""The area-averaged colour fold: checker corners are no less accurate at a high
oversample than at a low one (bilinear sampling of a denser atlas used to alias), and the
label image is still nearest-sampled."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import yaml

from rvmsim.render import cube_layout, fold, fold_color, nearest_labels, render_fisheye
from rvmsim.scene import checker_corners, scene_from_dict

from ..conftest import ROOT

BOARD_ONLY = ROOT / "docs" / "examples" / "board_only.yaml"


def _corner_rms(oversample: float, pose: dict, color_filter: str | None = None) -> float:
    """RMS (px) of cornerSubPix on the rendered board against cv2.fisheye.projectPoints
    (``color_filter`` None: the scene's default)."""
    d = yaml.safe_load(BOARD_ONLY.read_text())
    d["render"] = {"oversample": oversample}
    if color_filter is not None:
        d["render"]["color_filter"] = color_filter
    d["test_site"]["board"].update(pose)
    scene = scene_from_dict(d, base_dir=BOARD_ONLY.parent)
    cam = scene.fisheye_camera()
    grey = cv2.cvtColor(render_fisheye(scene).color, cv2.COLOR_RGB2GRAY)
    pts = np.array([c.point for c in checker_corners(scene) if c.name.startswith("board_inner")])
    rvec, tvec = cam.rvec_tvec
    proj = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K, cam.D)[0]
    crit = (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 50, 1e-4)
    found = cv2.cornerSubPix(grey, proj.astype(np.float32).copy(), (3, 3), (-1, -1), crit)
    err = np.linalg.norm(found.reshape(-1, 2) - proj.reshape(-1, 2), axis=1)
    return float(np.sqrt(np.mean(err**2)))


@pytest.mark.parametrize("pose", [
    pytest.param({}, marks=pytest.mark.slow),  # the tilted board below is the harder case
    {"position": [-0.3, -0.9, 0.9], "yaw_deg": -30.0, "pitch_deg": 25.0, "roll_deg": -15.0,
     "squares": [8, 10], "square_size": 0.05},
])
def test_corner_error_does_not_grow_with_oversample(pose):
    """On defaults (the area fold); one bilinear tap of a denser atlas aliases instead."""
    low, high = _corner_rms(1.5, pose), _corner_rms(3.5, pose)
    assert high < 0.1 and low < 0.1
    assert high <= low * 1.15 + 0.005
    bi_low, bi_high = _corner_rms(1.5, pose, "bilinear"), _corner_rms(3.5, pose, "bilinear")
    assert bi_high > 1.3 * bi_low and bi_high > 1.5 * high, (bi_low, bi_high, low, high)


def test_labels_stay_nearest_and_colour_is_an_average_of_the_atlas():
    d = yaml.safe_load(BOARD_ONLY.read_text())
    scene = scene_from_dict(d, base_dir=BOARD_ONLY.parent)
    cam = scene.fisheye_camera().scaled(0.25)
    layout = cube_layout(cam, face_size=64)
    rows, cols = layout.atlas_shape
    rng = np.random.default_rng(0)
    labels = rng.integers(1, 9, (rows, cols), dtype=np.uint8)
    # A constant colour atlas folds to that constant (inside the field), black outside.
    color = np.full((rows, cols, 3), 77, np.uint8)
    c, lab = fold(layout, color, labels)
    assert np.all(c[layout.in_fov] == 77) and np.all(c[~layout.in_fov] == 0)
    want = nearest_labels(labels, layout.atlas_x, layout.atlas_y)
    assert np.array_equal(lab[layout.in_fov], want[layout.in_fov])
    # A random atlas: each pixel lies between the atlas's extremes around its sample point.
    noise = rng.integers(0, 256, (rows, cols, 3), dtype=np.uint8)
    out = fold_color(layout, noise)
    assert out.dtype == np.uint8 and out[layout.in_fov].std() < noise.std()
