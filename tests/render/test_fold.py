"""Folding the atlas into the fisheye image: labels by nearest sampling (never blended),
colour bilinearly, SKY where nothing was hit, VOID outside the lens's field."""

from __future__ import annotations

import numpy as np

from rvmsim import labels as L
from rvmsim.camera import FisheyeCamera
from rvmsim.render import cube_layout, face_coords, fold


def _layout():
    cam = FisheyeCamera(160, 120, 30.0, 30.0, 79.5, 59.5, fov_deg=190.0)
    return cam, cube_layout(cam, face_size=80)


def test_labels_are_the_face_they_sample_and_colour_is_resampled():
    cam, layout = _layout()
    rows, cols = layout.atlas_shape
    label_atlas = np.zeros((rows, cols), np.uint8)
    color_atlas = np.zeros((rows, cols, 3), np.uint8)
    for crop in layout.crops:
        span = slice(crop.atlas_x0, crop.atlas_x0 + crop.width)
        label_atlas[: crop.height, span] = 10 + crop.face
        color_atlas[: crop.height, span] = 20 * (crop.face + 1)
    color, labels = fold(layout, color_atlas, label_atlas)
    rays, ok = cam.image_rays()
    face, _ = face_coords(rays, np.eye(3))
    assert labels.shape == (cam.height, cam.width) and labels.dtype == np.uint8
    np.testing.assert_array_equal(labels[ok], 10 + face[ok])
    assert np.all(labels[~ok] == L.VOID) and np.all(color[~ok] == 0)
    # A uniform crop resamples to its own value (the crops keep a margin for bilinear reads).
    np.testing.assert_array_equal(color[ok][:, 0], 20 * (face[ok] + 1))


def test_nothing_hit_is_sky_and_ids_are_not_blended():
    cam, layout = _layout()
    rows, cols = layout.atlas_shape
    rng = np.random.default_rng(0)
    label_atlas = rng.choice(np.array([0, 7, 200], np.uint8), size=(rows, cols))
    color, labels = fold(layout, np.zeros((rows, cols, 3), np.uint8), label_atlas)
    _, ok = cam.image_rays()
    assert set(np.unique(labels[ok]).tolist()) <= {L.SKY, 7, 200}
    assert L.SKY in set(np.unique(labels[ok]).tolist())
    # Nearest sampling: the label of each pixel is the atlas label at its rounded position.
    ix = np.floor(layout.atlas_x[ok] + 0.5).astype(int)
    iy = np.floor(layout.atlas_y[ok] + 0.5).astype(int)
    expected = label_atlas[iy, ix]
    np.testing.assert_array_equal(labels[ok], np.where(expected == 0, L.SKY, expected))
