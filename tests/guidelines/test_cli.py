"""``rvmsim guidelines``: its outputs, and bad ``vehicle`` and ``guidelines`` keys (one line,
exit status 2, nothing written)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
import yaml

from rvmsim.guidelines import compute_guidelines, guideline_view, steering_angles, running_gear
from rvmsim.guidelines.table import read_table, table_bytes
from rvmsim.isp import IspParams, OutputSpec, params_to_dict
from rvmsim.scene import load_scene
from rvmsim.testing.scenes import DELETE, write_small_scene
from tests.cli_runner import run_in_process

SMALL = {"display": {"rvm_image_px": [640, 360]}}


def _params(folder: Path, scale: float = 0.25) -> Path:
    path = folder / "setting.yaml"
    path.write_text(yaml.safe_dump(params_to_dict(IspParams(zoom=1.1).for_input_scale(scale),
                                                  OutputSpec())))
    return path


def test_outputs_match_the_library_and_the_table_hash(tmp_path: Path) -> None:
    scene = write_small_scene(tmp_path, "b", edit=SMALL)
    params = _params(tmp_path)
    out = tmp_path / "lines"
    res = run_in_process(["guidelines", scene, "--params", params, "--out", out,
                          "--steering", "-540:540:10", "--no-progress"])
    assert res.code == 0, res.stderr
    assert res.stderr == ""
    doc = json.loads((out / "guidelines.json").read_text())
    table = (out / "guidelines.bin").read_bytes()
    assert doc["table"]["sha256"] == hashlib.sha256(table).hexdigest()
    assert len(doc["trajectories"]) == 109
    assert doc["output"]["size"] == [640, 360]
    # the same set from the library, independently of the command's files
    sc = load_scene(scene)
    view = guideline_view(sc, IspParams(zoom=1.1).for_input_scale(0.25), OutputSpec())
    gset = compute_guidelines(sc, view, steering_angles(running_gear(sc), "-540:540:10"))
    assert table == table_bytes(gset)
    first = doc["static"][0]
    np.testing.assert_allclose(first["pieces"][0]["uv_px"], gset.static[0].pieces[0].uv_px,
                               atol=1e-4)
    assert read_table(table).width == 640
    picture = iio.imread(out / "guidelines.png")
    assert picture.shape == (360, 640, 3)
    # the picture is the RVM image with the lines: the 0.5 m mark's colour along its middle
    mid = gset.static[0].pieces[0].uv_px
    u, v = np.rint(mid[len(mid) // 2]).astype(int)
    assert tuple(picture[v, u]) == tuple(round(c * 255) for c in gset.static[0].color)
    svg = (out / "guidelines.svg").read_text()
    assert svg.count("<g id=\"steer_") == 109 and "data:image/jpeg;base64," in svg
    assert "covers" in doc


def test_check_judges_exit_0_when_the_lines_lie_on_their_painted_lines_1_when_not(
        tmp_path: Path) -> None:
    scene = write_small_scene(tmp_path, "a", edit={"display": {"rvm_image_px": [320, 180]}})
    params = _params(tmp_path)
    out = tmp_path / "lines"
    args = ["guidelines", scene, "--params", params, "--out", out, "--check", "--no-picture",
            "--steering", "0", "--no-progress"]
    res = run_in_process(args)
    assert res.code == 0, res.stderr
    doc = json.loads((out / "guidelines.json").read_text())
    check = doc["check"]
    assert check["G-1"]["pass"] and check["G-2"]["pass"]
    assert 0 < check["G-1"]["value_px"] <= 1.0
    kinds = {line["kind"] for line in check["lines"]}
    assert kinds == {"mark", "width", "trajectory"}
    assert "G-1 static lines" in res.stdout and "pass" in res.stdout
    # a limit no render meets: the same lines fail, exit 1, the files still written
    res = run_in_process([*args, "--limit-px", "0.01"])
    assert res.code == 1, res.stderr
    doc = json.loads((out / "guidelines.json").read_text())
    assert not doc["check"]["G-1"]["pass"] and doc["check"]["limit_px"] == 0.01
    assert "fail" in res.stdout


def _scene(tmp_path: Path, edit: dict[str, object]) -> Path:
    return write_small_scene(tmp_path, "a", edit={**SMALL, **edit})


BAD = [
    ("wheelbase-negative", {"vehicle.wheelbase": -1.0}, "vehicle.wheelbase"),
    ("wheelbase-missing", {"vehicle.wheelbase": DELETE}, "vehicle.wheelbase"),
    ("no-steering", {"vehicle.steering_ratio": DELETE}, "vehicle.steering_ratio"),
    ("both-steering", {"vehicle.steering_table": [[0, 0], [500, 35]]}, "vehicle"),
    ("table-not-increasing", {"vehicle.steering_ratio": DELETE,
                              "vehicle.steering_table": [[0, 0], [200, 20], [100, 30]]},
     "vehicle"),
    ("lock-nan", {"vehicle.max_road_wheel_deg": float("nan")}, "vehicle.max_road_wheel_deg"),
    ("mark-zero", {"guidelines": {"marks": [{"distance": 0}]}}, "guidelines.marks.0.distance"),
    ("marks-unordered", {"guidelines": {"marks": [{"distance": 2}, {"distance": 1}]}},
     "guidelines"),
    ("width-end-before-start", {"guidelines": {"width_lines": {"start": 2, "end": 1}}},
     "guidelines.width_lines"),
    ("unknown-key", {"guidelines": {"trajectory": {"travl": 3}}},
     "guidelines.trajectory.travl"),
    ("spec-file-missing", {"guidelines": "nowhere.yaml"}, "guidelines"),
]


@pytest.mark.parametrize("edit,key", [(e, k) for _, e, k in BAD], ids=[c for c, _, _ in BAD])
def test_bad_keys_are_one_line_and_nothing_is_written(tmp_path: Path, edit: dict[str, object],
                                                      key: str) -> None:
    scene = _scene(tmp_path, edit)
    out = tmp_path / "lines"
    res = run_in_process(["guidelines", scene, "--out", out, "--no-picture", "--no-progress"])
    assert res.code == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert str(scene) in lines[0] and key in lines[0], lines[0]
    assert not out.exists()


def test_a_bad_spec_file_is_named(tmp_path: Path) -> None:
    (tmp_path / "lines.yaml").write_text("marks:\n  - {distance: 1.0, color: [2, 0, 0]}\n")
    scene = _scene(tmp_path, {"guidelines": "lines.yaml"})
    out = tmp_path / "lines"
    res = run_in_process(["guidelines", scene, "--out", out, "--no-progress"])
    assert res.code == 2
    assert res.stderr.count("\n") == 1
    assert "lines.yaml" in res.stderr and "marks.0.color.0" in res.stderr
    assert not out.exists()
    # a good spec file is used
    (tmp_path / "lines.yaml").write_text("marks:\n  - {distance: 1.5}\n"
                                         "trajectory: {enabled: false}\n")
    res = run_in_process(["guidelines", scene, "--out", out, "--no-picture", "--no-progress",
                          "--steering", "0"])
    assert res.code == 0, res.stderr
    doc = json.loads((out / "guidelines.json").read_text())
    assert [l["name"] for l in doc["static"]] == ["mark_1.5m", "width_neg_x", "width_pos_x"]
    assert doc["trajectories"][0]["lines"] == []


def test_a_bad_steering_option_is_one_line(tmp_path: Path) -> None:
    scene = _scene(tmp_path, {})
    out = tmp_path / "lines"
    res = run_in_process(["guidelines", scene, "--out", out, "--steering", "5:1:1"])
    assert res.code == 2 and res.stderr.count("\n") == 1 and "--steering" in res.stderr
    assert not out.exists()
