"""The GL stage: real pyrender (EGL) renders of the cube faces, and the baked lighting."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.render import cube_layout, render_faces
from rvmsim.render.gl import AMBIENT, LIGHTS, _lambert, _linear_to_srgb
from rvmsim.scene import build_parts

from ..conftest import bundled_scene


def test_faces_render_into_the_atlas_with_the_parts_labels():
    scene = bundled_scene("a")
    cam = scene.fisheye_camera().scaled(0.1)
    layout = cube_layout(cam, face_size=48)
    parts = build_parts(scene)
    atlas = render_faces(parts, layout, cam, sky=scene.render.sky_color)
    assert atlas.color.shape[:2] == atlas.labels.shape == layout.atlas_shape
    present = set(np.unique(atlas.labels).tolist())
    assert present <= {p.label for p in parts} | {0}
    assert {L.GROUND, L.BUMPER, 0} <= present  # ground below, bumper in view, sky above
    assert atlas.gl_setup_s >= 0 and atlas.faces_s > 0
    # Each crop's columns hold its face: the face looking down the image (+y, toward the
    # ground and the car) sees no sky.
    down = [c for c in layout.crops if c.face == 2]
    assert down
    block = atlas.labels[: down[0].height, down[0].atlas_x0: down[0].atlas_x0 + down[0].width]
    assert np.all(block != 0)


def test_srgb_encoding_and_lambert_shading():
    np.testing.assert_allclose(_linear_to_srgb(np.array([0.0, 1.0, 2.0, -1.0])), [0, 1, 1, 0])
    x = np.array([0.0031308 - 1e-9, 0.0031308 + 1e-9])
    a, b = _linear_to_srgb(x)
    assert b == pytest.approx(a, abs=1e-6)  # continuous at the knee
    # A surface facing away from every light gets the ambient term only.
    away = np.array([direction / np.linalg.norm(direction) for direction, _ in LIGHTS[:1]])
    assert _lambert(away)[0] == pytest.approx(AMBIENT + sum(
        i * max(0.0, float(away[0] @ (-d / np.linalg.norm(d)))) for d, i in LIGHTS[1:]))
    up = np.array([[0.0, -1.0, 0.0]])
    assert _lambert(up)[0] > AMBIENT
