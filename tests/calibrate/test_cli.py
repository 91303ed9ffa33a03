"""``rvmsim calibrate`` end to end: rendered captures in, K/D/RMS per view, coverage picture,
camera block and an updated scene out; the camera block imports back to the same K/D."""

from __future__ import annotations

import json
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import yaml

from rvmsim.scene import load_scene

from ..cli_runner import Outcome, run_in_process
from ..conftest import ROOT
from .conftest import SQUARE, SQUARES
from .test_intrinsics import check_recovered


def _rvmsim(*args, cwd: Path) -> Outcome:
    return run_in_process(args, cwd=cwd)


def test_calibrate_writes_the_camera_and_updates_the_scene(board_views, tmp_path):
    scene_file = tmp_path / "scene.yaml"
    scene_file.write_text((ROOT / "docs" / "examples" / "board_only.yaml").read_text())
    before = yaml.safe_load(scene_file.read_text())
    board = f"{SQUARES[0] - 1}x{SQUARES[1] - 1}:{SQUARE}"
    res = _rvmsim("calibrate", board_views[0].parent, "--board", board, "--out", "cal",
                  "--write-scene", scene_file, cwd=tmp_path)
    assert res.code == 0, res.stderr
    assert "board found in 12 of 12 captures" in res.stdout
    doc = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    check_recovered(np.array(doc["K"]), np.array(doc["D"]))
    assert len(doc["views"]) == 12 and all(v["rms_px"] < 0.5 for v in doc["views"])
    cover = iio.imread(tmp_path / "cal" / "coverage.png")
    assert cover.shape == (480, 640, 3)
    green = (cover[..., 1] > 150) & (cover[..., 0] < 120)
    assert green[:, :100].any() and green[:, -100:].any()  # corners reached both sides
    # The scene: camera intrinsics and lens replaced, the mount, fov and the rest kept.
    after = yaml.safe_load(scene_file.read_text())
    assert after["camera"]["mount"] == before["camera"]["mount"]
    assert after["camera"]["lens"]["fov_deg"] == before["camera"]["lens"]["fov_deg"]
    assert {k: v for k, v in after.items() if k != "camera"} == \
        {k: v for k, v in before.items() if k != "camera"}
    cam = load_scene(scene_file).fisheye_camera()
    np.testing.assert_allclose(cam.K, np.array(doc["K"]), atol=1e-9)
    # The camera block imports back to the same K and D.
    res = _rvmsim("calibrate", "--import", "cal/camera.yaml", "--out", "again", cwd=tmp_path)
    assert res.code == 0, res.stderr
    again = yaml.safe_load((tmp_path / "again" / "camera.yaml").read_text())["camera"]
    np.testing.assert_allclose(again["intrinsics"]["K"], doc["K"], atol=1e-9)
    np.testing.assert_allclose(again["lens"]["k"], doc["D"], atol=1e-12)
