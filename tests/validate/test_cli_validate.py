"""`rvmsim validate`: outputs, the corrected scene, exit status and one-line errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from rvmsim.scene import load_scene

from .captures import perturbed, write_scene


def _run(*args: str, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "rvmsim", *args], capture_output=True,
                          text=True, timeout=600, env=env)


@pytest.fixture
def cache_env(tmp_path):
    return {**os.environ, "RVMSIM_CACHE": str(tmp_path / "cache")}


def test_cli_writes_outputs_and_a_corrected_scene_that_then_passes(tmp_path, cache_env):
    _, cap = perturbed()
    cap_file = tmp_path / "capture.png"
    cv2.imwrite(str(cap_file), cap[..., ::-1])
    scene_file = write_scene(tmp_path)
    out = tmp_path / "val"
    fixed = tmp_path / "fixed" / "mat_fixed.yaml"
    res = _run("validate", str(scene_file), "--capture", str(cap_file), "--out", str(out),
               "--write-scene", str(fixed), "--no-progress", env=cache_env)
    assert res.returncode == 1, res.stderr  # 0.8° yaw > 0.5°
    assert "verdict: FAIL" in res.stdout and "pose_angle_correction_deg" in res.stdout
    assert any(Path(cache_env["RVMSIM_CACHE"]).iterdir())  # rendered through the cache
    doc = json.loads((out / "validation.json").read_text())
    assert doc["passed"] is False and doc["landmarks"]["inliers"] >= 30
    for name in ("landmarks", "overlay", "edges", "overlay_corrected", "edges_corrected"):
        img = cv2.imread(str(out / f"{name}.png"))
        assert img is not None and img.shape == (480, 640, 3)
    html = (out / "validation.html").read_text()
    assert "Validation of" in html and html.count("data:image/png;base64,") == 5
    # The corrected scene keeps the comment and everything else, and now passes.
    text = fixed.read_text()
    assert text.startswith("# test scene")
    sc_fixed = load_scene(fixed)
    c = doc["pose_correction"]
    assert sc_fixed.camera.mount.yaw_deg == pytest.approx(c["yaw_deg"], abs=1e-3)
    assert list(sc_fixed.camera.mount.position) == pytest.approx(c["position_m"], abs=1e-4)
    assert sc_fixed.test_site == load_scene(scene_file).test_site
    res2 = _run("validate", str(fixed), "--capture", str(cap_file), "--out",
                str(tmp_path / "val2"), "--no-progress", env=cache_env)
    assert res2.returncode == 0, res2.stdout + res2.stderr
    assert "verdict: PASS" in res2.stdout


def test_cli_tolerances_gate_the_exit_status(tmp_path, cache_env):
    _, cap = perturbed()
    cap_file = tmp_path / "capture.png"
    cv2.imwrite(str(cap_file), cap[..., ::-1])
    scene_file = write_scene(tmp_path)
    res = _run("validate", str(scene_file), "--capture", str(cap_file), "--out",
               str(tmp_path / "v"), "--max-angle-deg", "1.0", "--no-progress", env=cache_env)
    assert res.returncode == 0, res.stdout + res.stderr
    res = _run("validate", str(scene_file), "--capture", str(cap_file), "--out",
               str(tmp_path / "v"), "--max-angle-deg", "1.0", "--max-rms-px", "0.01",
               "--no-progress", env=cache_env)
    assert res.returncode == 1
    assert "FAIL landmark_rms_after_correction_px" in res.stdout


@pytest.mark.parametrize("case", ["missing", "text", "empty", "blank", "size", "unrelated"])
def test_cli_bad_captures_are_one_line_errors(tmp_path, cache_env, case):
    scene_file = write_scene(tmp_path)
    cap = tmp_path / "cap.png"
    if case == "text":
        cap.write_text("not an image")
    elif case == "empty":
        cap.write_bytes(b"")
    elif case == "blank":
        cv2.imwrite(str(cap), np.zeros((480, 640), np.uint8))
    elif case == "size":
        cv2.imwrite(str(cap), np.random.default_rng(0).integers(0, 255, (640, 960), np.uint8))
    elif case == "unrelated":
        cv2.imwrite(str(cap), np.random.default_rng(0).integers(0, 255, (480, 640), np.uint8))
    expect = {"missing": "capture not found", "text": "cannot read capture",
              "empty": "empty file", "blank": "blank", "size": "960×640 px but the scene's "
              "camera.image_size is 640×480", "unrelated": "too few landmarks"}[case]
    res = _run("validate", str(scene_file), "--capture", str(cap), "--out", str(tmp_path / "v"),
               "--no-progress", env=cache_env)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.stderr, res.stderr
    assert expect in lines[0] and str(cap) in lines[0]
