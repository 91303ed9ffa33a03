"""`rvmsim validate`: outputs, the corrected scene, exit status and one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from rvmsim.scene import load_scene

from ..cli_runner import Outcome, run_in_process
from rvmsim.testing.captures import perturbed, write_scene


def _run(*args: str, env: dict | None = None) -> Outcome:
    return run_in_process(args, env=env)


@pytest.fixture
def cache_env(tmp_path):
    """A render cache of the test's own (the other tests share the session's: the same
    scene, rendered once)."""
    return {"RVMSIM_CACHE": str(tmp_path / "cache")}


def test_cli_writes_outputs_and_a_corrected_scene_that_then_passes(tmp_path, cache_env):
    _, cap = perturbed()
    cap_file = tmp_path / "capture.png"
    cv2.imwrite(str(cap_file), cap[..., ::-1])
    scene_file = write_scene(tmp_path)
    out = tmp_path / "val"
    fixed = tmp_path / "fixed" / "mat_fixed.yaml"
    res = _run("validate", str(scene_file), "--capture", str(cap_file), "--out", str(out),
               "--write-scene", str(fixed), "--no-progress", env=cache_env)
    assert res.code == 1, res.stderr  # 0.8° yaw > 0.5°
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
    assert res2.code == 0, res2.stdout + res2.stderr
    assert "verdict: PASS" in res2.stdout


def test_cli_failure_writes_its_pictures_and_names_the_step(tmp_path):
    scene_file = write_scene(tmp_path)
    cap = tmp_path / "noise.png"
    cv2.imwrite(str(cap), np.random.default_rng(1).integers(0, 255, (480, 640), np.uint8))
    out = tmp_path / "v"
    res = _run("validate", str(scene_file), "--capture", str(cap), "--out", str(out),
               "--no-progress")
    assert res.code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "(step failed: detection)" in lines[0], res.stderr
    assert str(out) in lines[0] and "--search-px" not in lines[0]
    assert "fit the capture's shade nowhere" in lines[0], lines[0]
    for name in ("overlay", "edges", "landmarks"):
        img = cv2.imread(str(out / f"{name}.png"))
        assert img is not None and img.shape == (480, 640, 3), name
    assert not (out / "validation.json").exists()


def test_cli_several_captures_give_one_table_and_one_page(tmp_path):
    """A folder plus a file: three captures, one passing (the scene's own frame), one failing
    its checks (the perturbed capture), one unrelated (an error, with its pictures)."""
    from rvmsim.testing.captures import base

    folder = tmp_path / "caps"
    folder.mkdir()
    cv2.imwrite(str(folder / "a_same.png"), base()[1].color[..., ::-1])
    cv2.imwrite(str(folder / "b_perturbed.png"), perturbed()[1][..., ::-1])
    (folder / "notes.txt").write_text("not a capture")
    noise = tmp_path / "noise.png"
    cv2.imwrite(str(noise), np.random.default_rng(2).integers(0, 255, (480, 640), np.uint8))
    scene_file = write_scene(tmp_path)
    out = tmp_path / "v"
    res = _run("validate", str(scene_file), "--capture", str(folder), "--capture", str(noise),
               "--out", str(out), "--no-progress")
    assert res.code == 2, res.stdout + res.stderr  # one capture is an error
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and "noise.png" in err[0] and "step failed: detection" in err[0]
    rows = json.loads((out / "summary.json").read_text())
    assert [Path(r["capture"]).name for r in rows] == ["a_same.png", "b_perturbed.png",
                                                       "noise.png"]
    assert [r["verdict"] for r in rows] == ["PASS", "FAIL", "ERROR"]
    assert rows[1]["step_failed"].startswith("check: ") and rows[2]["step_failed"] == "detection"
    csv_lines = (out / "summary.csv").read_text().splitlines()
    assert len(csv_lines) == 4 and csv_lines[0].startswith("capture,verdict,step_failed")
    for line, verdict in zip(res.stdout.splitlines()[2:5], ("PASS", "FAIL", "ERROR")):
        assert verdict in line, res.stdout
    page = (out / "validation.html").read_text()
    assert "1 of 3 captures pass" in page
    assert all(n in page for n in ("a_same.png", "b_perturbed.png", "noise.png"))
    assert page.count("<img") >= 3 + 3 + 3  # every capture's pictures, the error's too
    for sub in ("a_same", "b_perturbed"):
        assert json.loads((out / sub / "validation.json").read_text())["capture"].endswith(
            f"{sub}.png")
    assert (out / "noise" / "landmarks.png").is_file()


def test_cli_several_captures_a_failure_whose_pictures_cannot_be_written_is_a_row(
        tmp_path):
    """Several captures: one fails detection and its output folder cannot be made (a file
    is in the way). It is that capture's ERROR row and one line, not a traceback, and the
    other capture is still validated."""
    from rvmsim.testing.captures import base

    same = tmp_path / "a_same.png"
    cv2.imwrite(str(same), base()[1].color[..., ::-1])
    noise = tmp_path / "noise.png"
    cv2.imwrite(str(noise), np.random.default_rng(2).integers(0, 255, (480, 640), np.uint8))
    scene_file = write_scene(tmp_path)
    out = tmp_path / "v"
    out.mkdir()
    (out / "noise").write_text("in the way")
    res = _run("validate", str(scene_file), "--capture", str(same), "--capture", str(noise),
               "--out", str(out), "--no-progress")
    assert res.code == 2, res.stdout + res.stderr
    assert "Traceback" not in res.stderr
    err = res.stderr.strip().splitlines()
    assert len(err) == 1 and "noise" in err[0], res.stderr
    rows = json.loads((out / "summary.json").read_text())
    assert [r["verdict"] for r in rows] == ["PASS", "ERROR"]
