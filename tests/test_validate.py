"""Validation against captures: synthetic captures from perturbed scenes with known pose
errors (rendered with pyrender, then degraded like a real sensor), and the real BAIC EU5
frame in ../shared/reference/real-captures."""

from __future__ import annotations

import copy
import functools
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from rvmsim import labels as L
from rvmsim.validate import core as V
from rvmsim.camera import rotation_from_ypr
from rvmsim.errors import RvmsimError
from rvmsim.scene import checker_corners, pattern_shade
from rvmsim.render import render_fisheye
from rvmsim.scene import load_scene, scene_from_dict

from .conftest import ROOT, SCENES

def _real_captures() -> Path:
    """$RVMSIM_REAL_CAPTURES, else ../shared/reference/real-captures beside the checkout, else
    the team's reference folder on our machines (CI clones elsewhere)."""
    if os.environ.get("RVMSIM_REAL_CAPTURES"):
        return Path(os.environ["RVMSIM_REAL_CAPTURES"])
    for cand in (ROOT.parent / "shared" / "reference" / "real-captures",
                 Path("/work/shared/reference/real-captures")):
        if cand.is_dir():
            return cand
    return ROOT.parent / "shared" / "reference" / "real-captures"


BAIC = _real_captures() / "baic-eu5-rear" / "back.png"

MOUNT = {"position": [0.02, -0.97, -0.12], "yaw_deg": 0.5, "pitch_deg": 36.0, "roll_deg": -0.3}
#: The pose error of the perturbed capture: mm and degrees.
D_POS_MM = (6.0, -4.0, 8.0)
D_YPR_DEG = (0.8, -0.7, 0.5)


def _scene_dict(mount: dict = MOUNT) -> dict:
    """A sedan (vehicle A's body) on a 6 m × 2 m calibration mat with circle squares, side
    bands, an upright checkerboard behind the mat and the FMVSS objects; a Kannala-Brandt
    lens with fx ≠ fy and an off-centre principal point, 640 × 480."""
    d = yaml.safe_load((SCENES / "vehicle_a.yaml").read_text())
    d["camera"] = {
        "image_size": [640, 480],
        "intrinsics": {"fx": 200.0, "fy": 212.0, "cx": 322.3, "cy": 236.8},
        "lens": {"model": "kannala_brandt", "k": [-0.04, 0.003, -0.002, 0.0], "fov_deg": 196},
        "mount": copy.deepcopy(mount),
    }
    d["test_site"] = {
        "ground_patterns": [{
            "name": "mat", "origin": [-3.0, 0.5], "square_size": 0.4,
            "checker": [[0, 0, 6, 2], [0, -3, 1.8, 0], [4.2, -3, 6, 0]],
            "white": [[2.4, 0.4, 4.0, 2.0]],
            "circles": [[2.8, 0.8, 0.5], [3.6, 0.8, 0.5], [2.8, 1.6, 0.5], [3.6, 1.6, 0.5]],
        }],
        "board": {"placement": "upright", "position": [0.0, -0.75, 2.9], "squares": [5, 4],
                  "square_size": 0.2},
    }
    return d


def _scene(d: dict):
    return scene_from_dict(d, base_dir=SCENES)


def _perturbed_mount() -> dict:
    m = copy.deepcopy(MOUNT)
    m["position"] = [p + dp / 1000 for p, dp in zip(m["position"], D_POS_MM)]
    for key, dv in zip(("yaw_deg", "pitch_deg", "roll_deg"), D_YPR_DEG):
        m[key] += dv
    return m


@functools.lru_cache(maxsize=None)
def base():
    sc = _scene(_scene_dict())
    return sc, render_fisheye(sc)


def _paving(shape: tuple[int, int], seed: int) -> np.ndarray:
    """A texture unlike ours: dark discs on a light speckled ground (like concrete pavers)."""
    rng = np.random.default_rng(seed)
    tex = np.full(shape, 0.75, np.float32) + rng.normal(0, 0.06, shape).astype(np.float32)
    for _ in range(shape[0] * shape[1] // 300):
        c = (int(rng.integers(0, shape[1])), int(rng.integers(0, shape[0])))
        cv2.circle(tex, c, int(rng.integers(2, 6)), float(rng.uniform(0.3, 0.5)), -1)
    return tex


def _degrade(color: np.ndarray, labels: np.ndarray, seed: int = 0) -> np.ndarray:
    """Sensor-like capture: other ground texture, other exposure and gamma, vignetting,
    blur and noise."""
    img = color.astype(np.float32)
    ground = labels == L.GROUND
    img[ground] *= _paving(labels.shape, seed)[ground][:, None] * 1.2
    img = 255.0 * (np.clip(img, 0, 255) / 255.0) ** 1.25 * 0.8 + 6.0  # exposure, gamma, black
    h, w = labels.shape
    yy, xx = np.mgrid[:h, :w]
    r2 = ((xx - w / 2) ** 2 + (yy - h / 2) ** 2) / (w / 2) ** 2
    img *= (1.0 - 0.35 * r2)[..., None]
    img = cv2.GaussianBlur(img, (0, 0), 0.8)
    img += np.random.default_rng(seed).normal(0, 4.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


@functools.lru_cache(maxsize=None)
def perturbed():
    """The capture: perturbed pose, other paint, ground, mat and board colours, degraded."""
    d = _scene_dict(_perturbed_mount())
    d["vehicle"]["paint"] = [0.1, 0.2, 0.6]
    d["test_site"]["ground_color"] = [0.35, 0.3, 0.25]
    d["test_site"]["ground_patterns"][0]["white_color"] = [0.7, 0.7, 0.66]
    d["test_site"]["ground_patterns"][0]["black_color"] = [0.09, 0.08, 0.08]
    truth = render_fisheye(_scene(d))
    return truth, _degrade(truth.color, truth.labels)


# ---------------------------------------------------------------------------- geometry
def test_pattern_shade_matches_rendered_mat():
    """The analytic mat layout (used to tell checker shifts apart) is what the renderer draws:
    pixel rays hit the ground where pattern_shade says black or white, and the rendered
    colour agrees on ≥ 99 % of the mat's pixels away from the square borders."""
    sc, syn = base()
    cam = syn.camera
    mat = syn.labels == L.GROUND_PATTERN
    vv, uu = np.nonzero(mat)
    rays, _ = cam.pixel_rays(np.stack([uu, vv], axis=1).astype(float))
    d = rays @ cam.rotation.T
    t = (-0.004 - cam.position[1]) / d[:, 1]
    x, z = cam.position[0] + t * d[:, 0], cam.position[2] + t * d[:, 2]
    shade = pattern_shade(sc.test_site.ground_patterns[0], x, z)
    grey = cv2.cvtColor(syn.color, cv2.COLOR_RGB2GRAY)[vv, uu]
    # Stay 2 px clear of any black/white border (sampled shade differs at distance).
    border = cv2.dilate(cv2.Canny(cv2.cvtColor(syn.color, cv2.COLOR_RGB2GRAY), 50, 150),
                        np.ones((5, 5), np.uint8))[vv, uu] == 0
    assert np.isfinite(shade[border]).mean() > 0.99
    agree = (grey[border] > 128) == (shade[border] > 0.5)
    assert agree.mean() > 0.99, agree.mean()


def test_checker_corners_project_like_cv2_and_lie_on_rendered_saddles():
    """Every visible checker corner projects with our lens model as cv2.fisheye.projectPoints
    projects it (≤ 0.01 px), and the rendered frame has its saddle point there: cornerSubPix
    started 2 px off comes back within 0.6 px."""
    sc, syn = base()
    cam = syn.camera
    corners = checker_corners(sc)
    pts = np.array([c.point for c in corners])
    ours, _ = cam.project(pts)
    rvec, tvec = cam.rvec_tvec
    theirs, _ = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K, cam.D)
    front = cam.scene_to_camera(pts)[:, 2] > 0.05  # cv2's model stops at 90° off-axis
    assert front.sum() >= 60
    np.testing.assert_allclose(ours[front], theirs.reshape(-1, 2)[front], atol=0.01)
    spacing = V._spacing_px(cam, cam.position, cam.rotation, corners)
    usable = V._usable(cam, corners, syn.labels, ours, spacing)
    assert usable.sum() >= 30 and front[usable].all()
    grey = cv2.cvtColor(syn.color, cv2.COLOR_RGB2GRAY).astype(np.float32)
    errs = []
    for n in np.flatnonzero(usable):
        start = (ours[n] + [2.0, -1.5]).astype(np.float32).reshape(1, 1, 2)
        w = int(np.clip(round(0.3 * spacing[n]), 3, 12))
        p = cv2.cornerSubPix(grey, start, (w, w), (-1, -1),
                             (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
        errs.append(np.linalg.norm(p.ravel() - ours[n]))
    assert max(errs) < 0.6, max(errs)


# ---------------------------------------------------------------------------- validation
def test_unperturbed_capture_gives_no_correction():
    sc, syn = base()
    res = V.validate(sc, syn.color.copy(), synthetic=syn, rerender=False)
    assert res.passed
    assert res.n_inliers >= 35 and res.n_inliers == res.n_found
    # The renderer puts edges within 0.5 / oversample px of their place: ~0.2 px RMS.
    assert res.rms_before_px < 0.35 and res.rms_after_px < 0.35
    c = res.correction
    assert c.d_position_norm_mm < 5.0 and c.max_d_angle_deg < 0.1
    assert res.edges_before.chamfer_px < 0.05


@functools.lru_cache(maxsize=None)
def perturbed_validation(tamper: bool = True):
    sc, syn = base()
    truth, cap = perturbed()
    cap = cap.copy()
    tampered = []
    if tamper:
        # Three corners moved 5 px in the capture (a wrinkled mat): outliers to reject.
        corners = [c for c in checker_corners(sc) if c.label == L.GROUND_PATTERN]
        uv, _ = truth.camera.project(np.array([c.point for c in corners]))
        for n in (5, 12, 20):
            x, y = np.round(uv[n]).astype(int)
            patch = cap[y - 7:y + 8, x - 7:x + 8].copy()
            cap[y - 7:y + 8, x - 2:x + 8] = patch[:, :10]
            tampered.append(corners[n].name)
    res = V.validate(sc, cap, synthetic=syn, rerender=True)
    return res, tampered


def test_perturbed_capture_recovers_the_pose_error():
    res, tampered = perturbed_validation()
    c = res.correction
    for got, want in zip(c.d_position_mm, D_POS_MM):
        assert abs(got - want) <= 10.0, (c.d_position_mm, D_POS_MM)
    for got, want in zip((c.d_yaw_deg, c.d_pitch_deg, c.d_roll_deg), D_YPR_DEG):
        assert abs(got - want) <= 0.2, (got, want)
    assert res.rms_after_px <= 0.5
    assert res.rms_before_px > 3.0  # the error was there to find
    assert res.n_inliers >= 30
    # The moved corners are not among the inliers.
    by_name = {m.name: m for m in res.landmarks}
    assert all(not by_name[n].inlier for n in tampered if n in by_name)
    # The 0.8° yaw error fails the default 0.5° tolerance and says what to do.
    failed = [k for k in res.checks if not k.passed]
    assert [k.name for k in failed] == ["pose_angle_correction_deg"]
    assert "--write-scene" in failed[0].hint
    # After the correction the edges line up better than before.
    assert res.edges_after is not None
    assert res.edges_after.chamfer_px < res.edges_before.chamfer_px


def test_board_is_found_by_the_chessboard_detector():
    res, _ = perturbed_validation()
    board = [m for m in res.landmarks if m.name.startswith("board_inner")]
    assert len(board) == 12
    assert all(m.method == "chessboard" and m.inlier for m in board)
    assert max(m.error_after_px for m in board) < 1.0


def test_pose_fit_agrees_with_cv2_fisheye_solvepnp():
    """Our fit (in the scene's mount parameters) and OpenCV's fisheye PnP on the same
    inliers give the same camera pose."""
    res, _ = perturbed_validation()
    inl = [m for m in res.landmarks if m.inlier]
    pts = np.array([m.point for m in inl])
    uv = np.array([m.found_px for m in inl])
    sc, syn = base()
    cam = syn.camera
    ok, rvec, tvec = cv2.fisheye.solvePnP(pts.reshape(-1, 1, 3), uv.reshape(-1, 1, 2),
                                          cam.K, cam.D, flags=cv2.SOLVEPNP_ITERATIVE)
    assert ok
    r_sc, _ = cv2.Rodrigues(rvec)
    pos_cv = -r_sc.T @ tvec.ravel()
    c = res.correction
    rot = rotation_from_ypr(c.yaw_deg, c.pitch_deg, c.roll_deg)
    angle = math.degrees(np.arccos(np.clip((np.trace(rot.T @ r_sc.T) - 1) / 2, -1, 1)))
    assert angle < 0.05, angle  # cv2 minimises the error on the undistorted plane, we in px
    assert np.linalg.norm(pos_cv - np.array(c.position_m)) * 1000 < 2.0


def test_grossly_wrong_pose_fails_the_verdict():
    """A scene whose camera sits 60 mm lower and 3° off in pitch than the capture's."""
    sc, syn = base()
    _, cap = perturbed()
    d = _scene_dict({**MOUNT, "position": [0.02, -0.91, -0.12], "pitch_deg": 39.0})
    wrong = _scene(d)
    res = V.validate(wrong, cap, rerender=False)
    assert not res.passed
    names = {k.name for k in res.checks if not k.passed}
    assert names == {"pose_position_correction_mm", "pose_angle_correction_deg"}
    assert res.correction.d_pitch_deg == pytest.approx(-3.7, abs=0.2)
    assert res.correction.d_position_mm[1] == pytest.approx(-64.0, abs=10.0)
    assert res.rms_after_px < 0.5


def test_capture_of_something_else_is_an_error():
    sc, syn = base()
    noise = np.random.default_rng(3).integers(0, 255, syn.color.shape, dtype=np.uint8)
    with pytest.raises(RvmsimError, match="too few landmarks"):
        V.validate(sc, noise, synthetic=syn, rerender=False)
    with pytest.raises(RvmsimError, match="320×240 px but the scene's camera is 640×480"):
        V.validate(sc, syn.color[::2, ::2].copy(), synthetic=syn, rerender=False)


def test_rvm_comparison_and_ecs_follow_the_capture():
    """With ISP parameters: the capture's RVM image is compared with the synthetic one, and
    the ECs 'on the capture' (labels of the pose that explains it) are closer to the ECs of
    the true pose than the scene's are."""
    from rvmsim.criteria import evaluate
    from rvmsim.isp import IspParams, OutputSpec, process

    sc, syn = base()
    truth, cap = perturbed()
    params = IspParams().for_input_scale(640 / 1280)
    out = OutputSpec(320, 180)
    res = V.validate(sc, cap, synthetic=syn, params=params, output=out)
    assert res.rvm is not None
    ec_truth = evaluate(process(None, truth.labels, params, out)[1])
    diffs_scene, diffs_capture = [], []
    for item in ec_truth.items:
        vt, vs, vc = item.value, res.rvm.ec_scene[item.id].value, res.rvm.ec_capture[item.id].value
        if vt is None or vs is None or vc is None:
            continue
        diffs_scene.append(abs(vs - vt) / max(abs(vt), 1e-3))
        diffs_capture.append(abs(vc - vt) / max(abs(vt), 1e-3))
    assert len(diffs_scene) >= 6
    assert sum(diffs_capture) < 0.5 * sum(diffs_scene), (diffs_capture, diffs_scene)
    for key in ("rvm_capture", "rvm_synthetic", "rvm_overlay", "rvm_edges"):
        assert res.images[key].shape == (180, 320, 3)
    d = res.to_dict()
    assert set(d["rvm"]["ecs"]) == {i.id for i in ec_truth.items}


# ---------------------------------------------------------------------------- files, CLI
def _write_scene(tmp_path: Path, mount: dict = MOUNT, name: str = "mat.yaml") -> Path:
    d = _scene_dict(mount)
    text = "# test scene: a sedan on a calibration mat\n" + yaml.safe_dump(d, sort_keys=False)
    p = tmp_path / name
    p.write_text(text)
    return p


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
    scene_file = _write_scene(tmp_path)
    out = tmp_path / "val"
    fixed = tmp_path / "fixed" / "mat_fixed.yaml"
    res = _run("validate", str(scene_file), "--capture", str(cap_file), "--out", str(out),
               "--write-scene", str(fixed), "--no-progress", env=cache_env)
    assert res.returncode == 1, res.stderr  # 0.8° yaw > 0.5°
    assert "verdict: FAIL" in res.stdout and "pose_angle_correction_deg" in res.stdout
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
    scene_file = _write_scene(tmp_path)
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
    scene_file = _write_scene(tmp_path)
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


def test_load_capture_formats(tmp_path):
    rng = np.random.default_rng(1)
    grey16 = rng.integers(0, 65535, (48, 64), dtype=np.uint16)
    cv2.imwrite(str(tmp_path / "g16.png"), grey16)
    img = V.load_capture(tmp_path / "g16.png")
    assert img.shape == (48, 64, 3) and img.dtype == np.uint8
    assert np.array_equal(img[..., 0], (grey16 >> 8).astype(np.uint8))
    bgra = rng.integers(0, 255, (48, 64, 4), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / "c.png"), bgra)
    img = V.load_capture(tmp_path / "c.png")
    assert np.array_equal(img, bgra[..., 2::-1])


def test_write_corrected_scene_rewrites_block_lists_inserts_missing_angles(tmp_path):
    c = V.PoseCorrection((1.0, 2.0, 3.0), 0.1, 0.2, 0.3, (0, 0, 0), (0, 0, 0),
                         (0.021, -0.968, -0.117), 0.6, 36.2, -0.2)
    src = tmp_path / "s.yaml"
    d = _scene_dict({"position": [0.02, -0.97, -0.12]})  # no angles: they default to 0
    src.write_text("# keep me\n" + yaml.safe_dump(d, sort_keys=False))  # block-style lists
    assert "position:\n" in src.read_text()
    out = V.write_corrected_scene(src, c, tmp_path / "o.yaml")
    text = out.read_text()
    assert text.startswith("# keep me\n")
    m = load_scene(out).camera.mount
    assert (m.yaw_deg, m.pitch_deg, m.roll_deg) == (0.6, 36.2, -0.2)
    assert tuple(m.position) == (0.021, -0.968, -0.117)
    assert load_scene(out).test_site == load_scene(src).test_site
    odd = src.read_text().replace("    - 0.02\n", "    - !!float 0.02\n")
    src.write_text(odd)
    with pytest.raises(RvmsimError, match="camera.mount.position: cannot rewrite"):
        V.write_corrected_scene(src, c, tmp_path / "o2.yaml")


# ---------------------------------------------------------------------------- real frame
needs_real = pytest.mark.skipif(not BAIC.is_file(),
                                reason=f"real capture not found at {BAIC} "
                                       "(set RVMSIM_REAL_CAPTURES)")


@functools.lru_cache(maxsize=None)
def baic():
    sc = load_scene(SCENES / "real" / "baic_eu5_rear.yaml")
    cap = V.load_capture(BAIC, sc.fisheye_camera())
    return sc, cap, render_fisheye(sc)


@needs_real
def test_real_capture_matches_the_bundled_scene():
    """The bundled BAIC EU5 scene explains its real frame: ≥ 35 mat corners matched with
    RMS ≤ 2 px (≈ 0.7 px), and its mount pose needs no correction beyond the tolerances."""
    sc, cap, syn = baic()
    res = V.validate(sc, cap, synthetic=syn, capture_name=str(BAIC), rerender=False)
    assert res.n_inliers >= 35
    assert res.rms_after_px <= 2.0 and res.rms_before_px <= 2.0
    assert res.passed, res.summary()
    # The pose is plausible for a rear camera: the README's rough decomposition says
    # ~0.97 m up and ~38° down.
    c = res.correction
    assert 0.90 <= -c.position_m[1] <= 1.02
    assert 35.0 <= c.pitch_deg <= 40.0


@needs_real
def test_real_capture_from_the_rough_pose_finds_the_same_pose():
    """Starting from the capture README's rough pose (0.97 m, 38°, no yaw or roll, centred)
    the search lands on the bundled scene's pose: the periodic checker does not fool it."""
    sc, cap, syn = baic()
    rough = sc.camera.mount.model_copy(update={"position": (0.0, -0.97, -0.10),
                                               "yaw_deg": 0.0, "pitch_deg": 38.0,
                                               "roll_deg": 0.0})
    rough_scene = sc.model_copy(update={"camera": sc.camera.model_copy(update={"mount": rough})})
    res = V.validate(rough_scene, cap, capture_name=str(BAIC), rerender=False)
    m = sc.camera.mount
    c = res.correction
    assert res.rms_after_px <= 2.0 and res.n_inliers >= 35
    assert np.linalg.norm(np.subtract(c.position_m, m.position)) < 0.01
    assert abs(c.yaw_deg - m.yaw_deg) < 0.1
    assert abs(c.pitch_deg - m.pitch_deg) < 0.1
    assert abs(c.roll_deg - m.roll_deg) < 0.1
    assert res.rms_before_px > 5.0 and not res.passed
