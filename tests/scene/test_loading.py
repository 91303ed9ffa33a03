"""Reading scene files: one-line errors naming file, line and key; portable documents."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from rvmsim.errors import SceneError
from rvmsim.scene import MeshPart, load_scene, mesh_parts, scene_from_dict

from ..cli_runner import Outcome, run_in_process
from ..conftest import SCENES, bundled_scene
from .conftest import minimal_scene as _minimal


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


def _run_cli(*args: str) -> Outcome:
    return run_in_process(args)


#: One command-line case per error class (the values are the library's contract above):
#: a value the schema refuses, a document that is not YAML, one that is not a mapping.
CLI_CASES = [next(c for c in BAD_CASES if c[0] == "wrong type"),
             ("malformed", "name: [unclosed\ncamera: {", "", "malformed YAML"),
             ("not a mapping", "- just\n- a list\n", "", "mapping")]


@pytest.mark.parametrize("case, data, key, words", CLI_CASES, ids=[c[0] for c in CLI_CASES])
def test_bad_scene_cli_one_line_exit_2(tmp_path, case, data, key, words):
    path = _write(tmp_path, data)
    res = _run_cli("render", str(path), "--out", str(tmp_path / "out"), "--no-progress")
    assert res.code == 2
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
    assert res.code == 2 and "nope.yaml: file not found" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def test_absolute_mesh_paths_make_a_document_portable(tmp_path):
    """Vehicle F's mesh-file bumper: after absolute_mesh_paths the document loads from
    another folder (what sweep points and cluster tasks rely on)."""
    from rvmsim.scene import absolute_mesh_paths

    doc = yaml.safe_load((SCENES / "vehicle_f.yaml").read_text())
    paths = absolute_mesh_paths(doc, SCENES)
    assert paths and all(p.is_absolute() and p.is_file() for p in paths)
    assert doc["vehicle"]["bumper"]["mesh"] == str(paths[0])
    moved = tmp_path / "elsewhere"
    moved.mkdir()
    scene = scene_from_dict(doc, base_dir=moved)
    assert scene.resolve_path(scene.vehicle.bumper.mesh) == paths[0]


def test_mesh_parts_name_every_mesh_file_part():
    keys = [k for k, _ in mesh_parts(bundled_scene("f"))]
    assert keys == ["vehicle.bumper.mesh"]
    assert mesh_parts(bundled_scene("a")) == []
    data = _minimal()
    data["vehicle"]["extra"] = [{"mesh": str(SCENES.parent / "assets" / "bumper_rounded.stl")}]
    parts = mesh_parts(scene_from_dict(data))
    assert [k for k, _ in parts] == ["vehicle.extra.0.mesh"]
    assert isinstance(parts[0][1], MeshPart)


def test_the_image_pixel_limit_can_be_raised(monkeypatch):
    data = _mutate(["camera", "image_size"], [8000, 8000])
    data["camera"]["intrinsics"] = {"fx": 2500.0, "fy": 2500.0}
    with pytest.raises(SceneError, match="RVMSIM_MAX_IMAGE_PIXELS"):
        scene_from_dict(data)
    monkeypatch.setenv("RVMSIM_MAX_IMAGE_PIXELS", "64000000")
    assert scene_from_dict(data).camera.image_size == (8000, 8000)


def test_every_bundled_scene_passes_the_value_checks():
    from rvmsim.scene.loading import camera_problem

    for path in sorted(SCENES.glob("**/*.yaml")):
        assert camera_problem(load_scene(path).camera) is None, path
