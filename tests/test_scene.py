"""Scene files: the bundled vehicles, the intrinsics forms, overrides, and bad input."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from rvmsim.scene import fmvss111
from rvmsim.errors import SceneError
from rvmsim.scene import load_scene, scene_from_dict

from .conftest import SCENES, bundled_scene

LETTERS = "abcdef"


def _minimal() -> dict:
    return {
        "name": "t",
        "camera": {
            "image_size": [640, 480],
            "intrinsics": {"fx": 200.0, "fy": 200.0},
            "mount": {"position": [0.0, -1.0, -0.1], "pitch_deg": 30},
        },
        "vehicle": {"bumper": {"width": 1.8, "bottom": 0.3, "top": 0.6, "depth": 0.3}},
    }


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


# ------------------------------------------------------------------------------ bad input
def _write(tmp_path: Path, data: dict | str) -> Path:
    p = tmp_path / "scene.yaml"
    p.write_text(data if isinstance(data, str) else yaml.safe_dump(data))
    return p


def _mutate(path: list, value) -> dict:
    data = _minimal()
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is _DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


_DELETE = object()

BAD_CASES = [
    ("unknown key", _mutate(["camera", "lense"], {"fov_deg": 190}), "camera.lense", "unknown key"),
    ("missing key", _mutate(["camera", "mount"], _DELETE), "camera.mount", "missing"),
    ("wrong type", _mutate(["camera", "intrinsics", "fx"], "wide"), "camera.intrinsics.fx", "number"),
    ("focal <= 0", _mutate(["camera", "intrinsics", "fx"], -3.0), "camera.intrinsics.fx", "greater than 0"),
    ("image size <= 0", _mutate(["camera", "image_size"], [0, 480]), "camera.image_size.0", "greater than 0"),
    ("negative dim", _mutate(["vehicle", "bumper", "width"], -1.8), "vehicle.bumper.width", "greater than 0"),
    ("top below bottom", _mutate(["vehicle", "bumper", "top"], 0.1), "vehicle.bumper", "above bottom"),
    ("pitch out of range", _mutate(["camera", "mount", "pitch_deg"], 120), "camera.mount.pitch_deg", "less than or equal"),
    ("missing mesh", _mutate(["vehicle", "garnish"], {"mesh": "parts/nothere.stl"}), "vehicle.garnish.mesh", "not found"),
    ("bad lens", _mutate(["camera", "lens"], {"model": "kannala_brandt", "k": [-0.5, 0, 0, 0]}), "camera", "monotonic"),
]


@pytest.mark.parametrize("case, data, key, words", BAD_CASES, ids=[c[0] for c in BAD_CASES])
def test_bad_scene_library_error(tmp_path, case, data, key, words):
    path = _write(tmp_path, data)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    err = info.value
    assert err.file == str(path) and err.key == key
    assert words in err.message
    assert "\n" not in str(err)


def _run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "rvmsim", *args], capture_output=True, text=True, timeout=120
    )


@pytest.mark.parametrize(
    "case, data, key, words",
    BAD_CASES + [("malformed", "name: [unclosed\ncamera: {", "", "malformed YAML"),
                 ("not a mapping", "- just\n- a list\n", "", "mapping")],
    ids=[c[0] for c in BAD_CASES] + ["malformed", "not a mapping"],
)
def test_bad_scene_cli_one_line_exit_2(tmp_path, case, data, key, words):
    path = _write(tmp_path, data)
    res = _run_cli("render", str(path), "--out", str(tmp_path / "out"), "--no-progress")
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    assert str(path) in lines[0] and words in lines[0]
    if key:
        assert f": {key}: " in lines[0]
    assert not (tmp_path / "out").exists()


def test_error_names_the_line(tmp_path):
    text = (SCENES / "vehicle_a.yaml").read_text().replace("fx: 390.0", "fx: -390.0")
    path = _write(tmp_path, text)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    lineno = next(i for i, s in enumerate(text.splitlines(), 1) if "fx: -390.0" in s)
    assert info.value.line == lineno
    assert str(info.value).startswith(f"{path}:{lineno}: camera.intrinsics.fx:")


def test_missing_scene_file_cli(tmp_path):
    res = _run_cli("render", str(tmp_path / "nope.yaml"), "--out", str(tmp_path / "o"))
    assert res.returncode == 2 and "nope.yaml: file not found" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


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


def test_absolute_mesh_paths_make_a_document_portable(tmp_path):
    """Vehicle F's mesh-file bumper: after absolute_mesh_paths the document loads from
    another folder (what sweep points and cluster tasks rely on)."""
    import yaml

    from rvmsim.scene import absolute_mesh_paths, scene_from_dict

    doc = yaml.safe_load((SCENES / "vehicle_f.yaml").read_text())
    paths = absolute_mesh_paths(doc, SCENES)
    assert paths and all(p.is_absolute() and p.is_file() for p in paths)
    assert doc["vehicle"]["bumper"]["mesh"] == str(paths[0])
    moved = tmp_path / "elsewhere"
    moved.mkdir()
    scene = scene_from_dict(doc, base_dir=moved)
    assert scene.resolve_path(scene.vehicle.bumper.mesh) == paths[0]
