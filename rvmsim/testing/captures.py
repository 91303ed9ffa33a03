"""The captures the validation tests and benchmarks use: synthetic captures from perturbed scenes with known pose errors (rendered with
pyrender, then degraded like a real sensor), and the real BAIC EU5 frame in
../shared/reference/real-captures."""

from __future__ import annotations

import copy
import functools
import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from rvmsim import labels as L
from rvmsim.render import FisheyeImages, render_fisheye
from rvmsim.scene import Scene, checker_corners, load_scene, scene_from_dict
from rvmsim.pose import load_capture
from rvmsim.validate import Validation, ValidationSettings, validate

from .scenes import ROOT, SCENES


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

MOUNT: dict[str, Any] = {"position": [0.02, -0.97, -0.12], "yaw_deg": 0.5, "pitch_deg": 36.0, "roll_deg": -0.3}
#: The pose error of the perturbed capture: mm and degrees.
D_POS_MM = (6.0, -4.0, 8.0)
D_YPR_DEG = (0.8, -0.7, 0.5)


def scene_dict(mount: dict = MOUNT) -> dict:
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


def make_scene(d: dict) -> Scene:
    return scene_from_dict(d, base_dir=SCENES)


def wrong_scene() -> Scene:
    """The test scene with its camera 60 mm lower and 3° off in pitch (vs the capture's)."""
    return make_scene(scene_dict({**MOUNT, "position": [0.02, -0.91, -0.12], "pitch_deg": 39.0}))


def perturbed_mount() -> dict:
    m = copy.deepcopy(MOUNT)
    m["position"] = [p + dp / 1000 for p, dp in zip(m["position"], D_POS_MM)]
    for key, dv in zip(("yaw_deg", "pitch_deg", "roll_deg"), D_YPR_DEG):
        m[key] += dv
    return m


@functools.lru_cache(maxsize=None)
def base() -> tuple[Scene, FisheyeImages]:
    sc = make_scene(scene_dict())
    return sc, render_fisheye(sc)


def _paving(shape: tuple[int, int], seed: int) -> np.ndarray:
    """A texture unlike ours: dark discs on a light speckled ground (like concrete pavers)."""
    rng = np.random.default_rng(seed)
    tex = np.full(shape, 0.75, np.float32) + rng.normal(0, 0.06, shape).astype(np.float32)
    for _ in range(shape[0] * shape[1] // 300):
        c = (int(rng.integers(0, shape[1])), int(rng.integers(0, shape[0])))
        cv2.circle(tex, c, int(rng.integers(2, 6)), float(rng.uniform(0.3, 0.5)), -1)
    return tex


def degrade(color: np.ndarray, labels: np.ndarray, seed: int = 0) -> np.ndarray:
    """Sensor-like capture: other ground texture, other exposure and gamma, vignetting,
    blur and noise."""
    img: np.ndarray = color.astype(np.float32)
    ground = labels == L.GROUND
    img[ground] *= _paving(labels.shape, seed)[ground][:, None] * 1.2
    img = 255.0 * (np.clip(img, 0, 255) / 255.0) ** 1.25 * 0.8 + 6.0  # exposure, gamma, black
    h, w = labels.shape
    yy, xx = np.mgrid[:h, :w]
    r2 = ((xx - w / 2) ** 2 + (yy - h / 2) ** 2) / (w / 2) ** 2
    img *= (1.0 - 0.35 * r2)[..., None]
    img = cv2.GaussianBlur(img, (0, 0), 0.8)
    np.add(img, np.random.default_rng(seed).normal(0, 4.0, img.shape), out=img)  # as +=
    return np.clip(img, 0, 255).astype(np.uint8)


@functools.lru_cache(maxsize=None)
def perturbed() -> tuple[FisheyeImages, np.ndarray]:
    """The capture: perturbed pose, other paint, ground, mat and board colours, degraded.
    Returns the true frame and the capture."""
    d = scene_dict(perturbed_mount())
    d["vehicle"]["paint"] = [0.1, 0.2, 0.6]
    d["test_site"]["ground_color"] = [0.35, 0.3, 0.25]
    d["test_site"]["ground_patterns"][0]["white_color"] = [0.7, 0.7, 0.66]
    d["test_site"]["ground_patterns"][0]["black_color"] = [0.09, 0.08, 0.08]
    truth = render_fisheye(make_scene(d))
    return truth, degrade(truth.color, truth.labels)


@functools.lru_cache(maxsize=None)
def perturbed_validation(tamper: bool = True) -> tuple[Validation, list[str]]:
    """Validation of the base scene against the perturbed capture (re-rendered at the
    corrected pose); with ``tamper``, three mat corners moved 5 px in the capture (a
    wrinkled mat): outliers to reject.  Returns the result and the moved corners' names."""
    sc, syn = base()
    truth, cap = perturbed()
    cap = cap.copy()
    tampered = []
    if tamper:
        corners = [c for c in checker_corners(sc) if c.label == L.GROUND_PATTERN]
        uv, _ = truth.camera.project(np.array([c.point for c in corners]))
        for n in (5, 12, 20):
            x, y = np.round(uv[n]).astype(int)
            patch = cap[y - 7:y + 8, x - 7:x + 8].copy()
            cap[y - 7:y + 8, x - 2:x + 8] = patch[:, :10]
            tampered.append(corners[n].name)
    res = validate(sc, cap, ValidationSettings(rerender=True), synthetic=syn)
    return res, tampered


@functools.lru_cache(maxsize=None)
def baic() -> tuple[Scene, np.ndarray, FisheyeImages]:
    """The bundled BAIC EU5 scene, its real frame, and the scene's render."""
    sc = load_scene(SCENES / "real" / "baic_eu5_rear.yaml")
    cap = load_capture(BAIC, sc.fisheye_camera())
    return sc, cap, render_fisheye(sc)


def baic_rough_scene(sc: Scene) -> Scene:
    """``sc`` with the capture README's rough pose (0.97 m, 38°, no yaw or roll, centred)."""
    return sc.with_mount((0.0, -0.97, -0.10), 0.0, 38.0, 0.0)


def write_scene(tmp_path: Path, mount: dict = MOUNT, name: str = "mat.yaml") -> Path:
    """The test scene as a YAML file with a leading comment."""
    d = scene_dict(mount)
    text = "# test scene: a sedan on a calibration mat\n" + yaml.safe_dump(d, sort_keys=False)
    p = tmp_path / name
    p.write_text(text)
    return p


#: The board-only scene's true mount and board (7 × 9 squares of 0.08 m: 48 inner corners).
BOARD_MOUNT: dict[str, Any] = {"position": [0.03, -1.0, -0.1], "yaw_deg": 1.0, "pitch_deg": 25.0,
               "roll_deg": 0.5}
BOARD_SQUARE_M = 0.08


def board_scene(d_position_m: tuple[float, float, float] = (0.0, 0.0, 0.0),
                d_ypr_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Scene:
    """A board-dominant scene: an upright checkerboard 1.1 m behind the camera, no test
    objects or guidelines, 640 × 480; the mount moved by ``d_position_m`` (m) and turned by
    ``d_ypr_deg`` (degrees)."""
    d = yaml.safe_load((SCENES / "vehicle_a.yaml").read_text())
    mount = copy.deepcopy(BOARD_MOUNT)
    mount["position"] = [p + dp for p, dp in zip(mount["position"], d_position_m)]
    for key, dv in zip(("yaw_deg", "pitch_deg", "roll_deg"), d_ypr_deg):
        mount[key] += dv
    d["camera"] = {
        "image_size": [640, 480],
        "intrinsics": {"fx": 200.0, "fy": 204.0, "cx": 321.0, "cy": 238.5},
        "lens": {"model": "kannala_brandt", "k": [-0.04, 0.003, -0.002, 0.0], "fov_deg": 190},
        "mount": mount,
    }
    d["test_site"] = {
        "objects": {k: {"enabled": False} for k in "ABCDEFG"},
        "guidelines": {"enabled": False},
        "board": {"placement": "upright", "position": [0.0, -0.7, 1.0],
                  "squares": [7, 9], "square_size": BOARD_SQUARE_M},
    }
    return make_scene(d)


@functools.lru_cache(maxsize=None)
def board_capture() -> np.ndarray:
    """The board-only scene's frame at its true pose, degraded like a sensor."""
    truth = render_fisheye(board_scene())
    return degrade(truth.color, truth.labels, seed=3)


def moved_scene(sc: Scene, d: tuple[float, ...]) -> Scene:
    """``sc`` with its mount moved by ``d[:3]`` (m, scene frame: y down) and turned by
    ``d[3:]`` (yaw, pitch, roll, degrees): a pose search's start that far off."""
    m = sc.camera.mount
    return sc.with_mount([p + dp for p, dp in zip(m.position, d[:3])], m.yaw_deg + d[3],
                         m.pitch_deg + d[4], m.roll_deg + d[5])


def moved_mount(d_position_m: tuple[float, float, float],
                d_ypr_deg: tuple[float, float, float]) -> dict:
    """:data:`MOUNT` moved by ``d_position_m`` (m) and turned by ``d_ypr_deg`` (degrees)."""
    m = copy.deepcopy(MOUNT)
    m["position"] = [p + dp for p, dp in zip(m["position"], d_position_m)]
    for key, dv in zip(("yaw_deg", "pitch_deg", "roll_deg"), d_ypr_deg):
        m[key] += dv
    return m
