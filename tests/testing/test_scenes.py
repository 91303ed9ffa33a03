"""The small scenes of the tests (rvmsim/testing/scenes.py): every bundled vehicle on a fraction of its
sensor is the camera ``rvmsim render --scale`` makes, whatever form its intrinsics take."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from rvmsim.scene import load_scene

from ..conftest import bundled_scene
from rvmsim.testing.scenes import apply_edits, load_small_scene, small_scene_doc, write_small_scene

LETTERS = "abcdef"  # fx/fy; fx/fy/cx/cy; horizontal fov; K; mm and µm; a mesh bumper


@pytest.mark.parametrize("scale", [0.25, 0.5])
@pytest.mark.parametrize("letter", LETTERS)
def test_the_small_camera_is_the_scaled_camera(letter: str, scale: float) -> None:
    small = load_small_scene(letter, scale).fisheye_camera()
    scaled = bundled_scene(letter).fisheye_camera().scaled(scale)
    for name in ("width", "height", "fx", "fy", "cx", "cy", "skew", "fov_deg"):
        assert getattr(small, name) == pytest.approx(getattr(scaled, name), rel=1e-12,
                                                     abs=1e-12), name
    np.testing.assert_array_equal(small.k, scaled.k)
    np.testing.assert_array_equal(small.rotation, scaled.rotation)
    np.testing.assert_array_equal(small.position, scaled.position)


@pytest.mark.parametrize("letter", LETTERS)
def test_a_scene_point_lands_where_the_full_sensor_sees_it_scaled(letter: str) -> None:
    """Independent of FisheyeCamera.scaled: a point seen at (u, v) on the full sensor is at
    ((u + 0.5) / 4 − 0.5, (v + 0.5) / 4 − 0.5) on the quarter sensor (pixel centres at
    integers, the image scaled about its edges)."""
    full = bundled_scene(letter).fisheye_camera()
    small = load_small_scene(letter).fisheye_camera()
    points = np.array([[0.0, 0.0, 1.0], [0.6, 0.2, 2.0], [-1.0, 0.5, 1.5], [0.3, 1.0, 0.8]])
    uv_full, _ = full.project(points)
    uv_small, _ = small.project(points)
    np.testing.assert_allclose(uv_small, (uv_full + 0.5) / 4 - 0.5, atol=1e-9)


def test_the_file_loads_anywhere_and_keeps_everything_else(tmp_path: Path) -> None:
    """Written into another folder (vehicle F's mesh path made absolute), the file is the
    bundled scene but for the camera's pixel values."""
    path = write_small_scene(tmp_path, "f")
    assert path.name == "vehicle_f.yaml"
    scene, full = load_scene(path), bundled_scene("f")
    small_vehicle, full_vehicle = scene.vehicle.model_dump(), full.vehicle.model_dump()
    mesh = small_vehicle["bumper"].pop("mesh")
    assert Path(mesh).is_absolute() and Path(mesh) == full.resolve_path(
        full_vehicle["bumper"].pop("mesh"))
    assert small_vehicle == full_vehicle
    assert scene.test_site == full.test_site and scene.variation == full.variation
    assert scene.camera.mount == full.camera.mount and scene.camera.lens == full.camera.lens


def test_variation_kept_removed_or_replaced() -> None:
    assert small_scene_doc("a")["variation"] == yaml.safe_load(
        (Path(__file__).parents[2] / "scenes" / "vehicle_a.yaml").read_text())["variation"]
    assert "variation" not in small_scene_doc("a", variation=None)
    mine = {"mount": {"yaw_deg": {"uniform": {"half_width": 2.0}}}}
    assert small_scene_doc("a", variation=mine)["variation"] == mine


def test_dotted_edits_set_index_create_and_delete() -> None:
    doc = {"a": {"b": 1, "c": [{"d": 2}, {"d": 3}]}}
    apply_edits(doc, {"a.b": 5, "a.c.1.d": 7, "x.y.z": 1, "a.c.0": None})
    assert doc == {"a": {"b": 5, "c": [{"d": 7}]}, "x": {"y": {"z": 1}}}
    apply_edits(doc, {"a.b": None, "a.nothing": None})
    assert doc == {"a": {"c": [{"d": 7}]}, "x": {"y": {"z": 1}}}
    edited = small_scene_doc("b", edit={"camera.intrinsics.cx": 100.0, "vehicle.paint": None})
    assert edited["camera"]["intrinsics"]["cx"] == 100.0 and "paint" not in edited["vehicle"]
