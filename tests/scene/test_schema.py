"""The scene schema: the bundled vehicles, the intrinsics forms, test-site defaults and
overrides, the documented example."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml

from rvmsim.camera import rotation_from_ypr
from rvmsim.scene import fmvss111, scene_from_dict

from ..conftest import SCENES, bundled_scene
from .conftest import minimal_scene as _minimal

LETTERS = "abcdef"


@pytest.mark.parametrize("letter", LETTERS)
def test_bundled_vehicles_are_plausible(letter):
    scene = bundled_scene(letter)
    cam = scene.fisheye_camera()
    height = -cam.position[1]
    assert 0.8 <= height <= 1.3, "camera height outside 0.8–1.3 m"
    assert 15 <= scene.camera.mount.pitch_deg <= 45
    assert (cam.width, cam.height) == (1280, 960)
    # The camera sits ahead of (or at) the bumper's rearmost plane, inside the car's width.
    assert cam.position[2] <= 0 and abs(cam.position[0]) < 0.3
    # Every FMVSS object is in front of the camera's principal plane and inside its field.
    for letter_ in "ABCDEFG":
        x, z = scene.test_site.object_centre(letter_)
        uv, ok = cam.project(np.array([[x, -0.4, z]]))
        assert ok[0] and 0 <= uv[0, 0] < cam.width and 0 <= uv[0, 1] < cam.height


def test_bundled_mix_four_sedans_two_suvs():
    kinds = [("SUV" in bundled_scene(v).name) for v in LETTERS]
    assert sum(kinds) == 2 and len(kinds) - sum(kinds) == 4
    heights = {round(-bundled_scene(v).fisheye_camera().position[1], 2) for v in LETTERS}
    pitches = {bundled_scene(v).camera.mount.pitch_deg for v in LETTERS}
    assert len(heights) == 6 and len(pitches) == 6  # all different mounts
    assert any(abs(bundled_scene(v).fisheye_camera().position[0]) > 0.01 for v in LETTERS)


def test_intrinsics_forms():
    base = _minimal()
    base["camera"]["intrinsics"] = {"horizontal_fov_deg": 180}
    cam = scene_from_dict(base).fisheye_camera()
    assert math.isclose(cam.fx, 320 / (math.pi / 2)) and cam.fx == cam.fy
    assert (cam.cx, cam.cy) == (319.5, 239.5)
    base["camera"]["intrinsics"] = {"focal_length_mm": 1.2, "pixel_pitch_um": 3.0}
    assert math.isclose(scene_from_dict(base).fisheye_camera().fx, 400.0)
    base["camera"]["intrinsics"] = {"K": [[300.0, 0.6, 320.0], [0, 310.0, 250.0], [0, 0, 1]]}
    base["camera"]["lens"] = {"model": "kannala_brandt", "k": [-0.01, 0.002, 0.0, 0.0]}
    cam = scene_from_dict(base).fisheye_camera()
    np.testing.assert_allclose(cam.K, [[300.0, 0.6, 320.0], [0, 310.0, 250.0], [0, 0, 1]])
    np.testing.assert_allclose(cam.D.ravel(), [-0.01, 0.002, 0.0, 0.0])


def test_test_site_defaults_and_overrides():
    scene = scene_from_dict(_minimal())
    site = scene.test_site
    for letter, xz in fmvss111.OBJECT_POSITIONS_M.items():
        assert site.object_centre(letter) == xz
    assert site.object_height == 0.8 and site.object_diameter == 0.3
    data = _minimal()
    data["test_site"] = {
        "objects": {"B": {"position": [0.2, 7.0]}, "D": {"enabled": False}},
        "position_reference": "surface",
        "guidelines": {"cross_z": [1.0, 2.0, 3.0]},
        "board": {"placement": "upright", "position": [0.0, -0.6, 4.0], "squares": [6, 4]},
    }
    site = scene_from_dict(data).test_site
    assert site.object_centre("B") == (0.2, 7.0 + 0.15)
    assert site.object_centre("D") is None
    assert site.guidelines.cross_z == [1.0, 2.0, 3.0]
    assert site.board.size == pytest.approx((6 * 0.14 + 0.08, 4 * 0.14 + 0.08))


def test_mesh_paths_resolve_relative_to_scene_file(tmp_path):
    scene = bundled_scene("f")
    assert scene.resolve_path(scene.vehicle.bumper.mesh) == (
        SCENES.parent / "assets" / "bumper_rounded.stl"
    ).resolve()


def test_documented_example_is_a_valid_scene():
    """docs/scene-format.md's complete example loads (with the bundled STL for its meshes)."""
    doc = (SCENES.parent / "docs" / "scene-format.md").read_text()
    block = doc.split("```yaml\n", 1)[1].split("```", 1)[0]
    text = block.replace("../assets/trunk.stl", "../assets/bumper_rounded.stl")
    text = text.replace("../assets/tow_hitch.stl", "../assets/bumper_rounded.stl")
    data = yaml.safe_load(text)
    scene = scene_from_dict(data, base_dir=SCENES, text=text)
    assert scene.camera.intrinsics.fx == 390.0
    assert scene.test_site.object_centre("D") is None
    assert scene.vehicle.trunk.units == "mm"


def test_with_mount_places_the_camera_where_asked_and_changes_nothing_else():
    """The camera of ``Scene.with_mount`` is at the given position, with the rotation the
    angles make (:func:`rvmsim.camera.rotation_from_ypr`, independent of the scene code), and
    a scene read from a document with that mount is the same scene."""
    doc = _minimal()
    sc = scene_from_dict(doc)
    moved = sc.with_mount((0.05, -1.1, -0.2), 2.5, 31.0, -1.25)
    cam = moved.fisheye_camera()
    np.testing.assert_allclose(cam.position, (0.05, -1.1, -0.2), atol=1e-12)
    np.testing.assert_allclose(cam.rotation, rotation_from_ypr(2.5, 31.0, -1.25), atol=1e-12)
    doc["camera"]["mount"] = {"position": [0.05, -1.1, -0.2], "yaw_deg": 2.5,
                              "pitch_deg": 31.0, "roll_deg": -1.25}
    assert moved == scene_from_dict(doc)
    assert sc.camera.mount != moved.camera.mount  # the original is left as it was
