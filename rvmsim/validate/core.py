"""Validate a scene against a real capture from the vehicle's rear-view camera.

A tuning is only worth as much as the synthetic frame it is tuned on.  :func:`validate`
compares the scene's rendered fisheye frame with a capture of the physical camera at the
test site and says what to fix in the scene:

1. **Landmarks.**  Every inner checker corner of the scene (the calibration board's, the
   ground patterns') is predicted from the scene (:func:`rvmsim.meshes.checker_corners`),
   kept if the rendered label image shows it unoccluded, and found in the capture: the
   board with OpenCV's chessboard detector where it is visible whole, every other corner
   by normalised cross-correlation of the rendered neighbourhood within a search radius
   (the colours of a checker corner's four squares make the match polarity-safe against
   its neighbours) followed by ``cv2.cornerSubPix``.  Saddle points refine without bias,
   which is why plain corners (guideline ends, outer mat corners) are not used.
2. **Pose.**  The mount pose that best explains the found corners is fitted by fisheye PnP:
   Levenberg-Marquardt over Δposition (m) and Δyaw/pitch/roll (degrees) of the scene's own
   mount parameters with our Kannala-Brandt projection, robust (soft-L1) first, then
   least squares on the inliers (residual ≤ max(1 px, 3 robust σ)).  Matching and fitting
   alternate three times with a shrinking search radius.  Standard errors come from the
   Jacobian.
3. **Edges.**  Canny edges of both images, symmetric chamfer distance over the part of the
   view the scene models (no void, no sky), distances truncated at
   :data:`CHAMFER_TRUNCATE_PX` so unmodelled clutter counts as "far" and not as infinity.
4. **RVM** (with ISP parameters): the capture and the synthetic frame through our ISP,
   edge comparison of the two RVM images, and the ECs of the scene's labels against the
   ECs of the labels of the pose-corrected scene (the synthetic frame that explains the
   capture; a capture has no labels of its own).
5. **Verdict** against :class:`Tolerances`.

Pixel convention: pixel centres at integer coordinates, as in :mod:`rvmsim.camera`.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera, rotation_from_ypr
from ..errors import RvmsimError
from ..tune.store import json_default
from ..scene import PATTERN_LIFT_M, CheckerCorner, checker_corners, pattern_axes, pattern_shade
from ..render import FisheyeImages
from ..scene import Scene

__all__ = [
    "Tolerances",
    "LandmarkMatch",
    "PoseCorrection",
    "EdgeComparison",
    "RvmComparison",
    "Check",
    "Validation",
    "load_capture",
    "find_landmarks",
    "fit_pose",
    "compare_edges",
    "validate",
    "write_outputs",
    "write_corrected_scene",
    "scene_with_mount",
    "CHAMFER_TRUNCATE_PX",
]

#: Edge distances above this count as this much in the chamfer mean, px.
CHAMFER_TRUNCATE_PX = 10.0
#: Minimum normalised cross-correlation for a local match to count as found.
MIN_NCC = 0.6
#: Corners whose neighbours are closer than this in the image are too small to use, px.
MIN_SPACING_PX = 8.0


# ---------------------------------------------------------------------------- results
@dataclass(frozen=True)
class Tolerances:
    """What a scene must meet to pass validation.

    Attributes
    ----------
    max_rms_px : float
        Landmark RMS error after the pose correction: intrinsics, lens and layout must
        explain the capture this well.
    max_position_mm : float
        Length of the mount position correction.
    max_angle_deg : float
        Largest of |Δyaw|, |Δpitch|, |Δroll|.
    max_chamfer_px : float or None
        Symmetric edge chamfer of the scene as given; None: reported, not judged.
    min_landmarks : int
        Fewer matched landmarks than this is an error, not a verdict.
    """

    max_rms_px: float = 2.0
    max_position_mm: float = 30.0
    max_angle_deg: float = 0.5
    max_chamfer_px: float | None = None
    min_landmarks: int = 8


@dataclass(frozen=True)
class LandmarkMatch:
    """One predicted landmark and where it was found in the capture (px).

    ``predicted_px`` uses the scene's mount pose, ``corrected_px`` the fitted one.
    ``method`` is ``"chessboard"``, ``"local"`` or ``""`` (not found); ``ncc`` is the
    match's normalised cross-correlation (1.0 for the chessboard detector).
    """

    name: str
    point: tuple[float, float, float]
    predicted_px: tuple[float, float]
    found_px: tuple[float, float] | None
    corrected_px: tuple[float, float]
    method: str
    ncc: float
    inlier: bool

    @property
    def error_before_px(self) -> float | None:
        if self.found_px is None:
            return None
        return math.dist(self.found_px, self.predicted_px)

    @property
    def error_after_px(self) -> float | None:
        if self.found_px is None:
            return None
        return math.dist(self.found_px, self.corrected_px)


@dataclass(frozen=True)
class PoseCorrection:
    """The mount pose change that best explains the capture.

    Attributes
    ----------
    d_position_mm : (3,) float
        Δx, Δy, Δz of the optical centre, scene frame, mm (Δy < 0: higher).
    d_yaw_deg, d_pitch_deg, d_roll_deg : float
        Changes of the scene's mount angles, degrees.
    sigma_position_mm, sigma_angles_deg : (3,) float
        One standard error of each, from the fit's Jacobian and residual.
    position_m : (3,) float
        The corrected mount position, m.
    yaw_deg, pitch_deg, roll_deg : float
        The corrected mount angles, degrees.
    """

    d_position_mm: tuple[float, float, float]
    d_yaw_deg: float
    d_pitch_deg: float
    d_roll_deg: float
    sigma_position_mm: tuple[float, float, float]
    sigma_angles_deg: tuple[float, float, float]
    position_m: tuple[float, float, float]
    yaw_deg: float
    pitch_deg: float
    roll_deg: float

    @property
    def d_position_norm_mm(self) -> float:
        return float(np.linalg.norm(self.d_position_mm))

    @property
    def max_d_angle_deg(self) -> float:
        return max(abs(self.d_yaw_deg), abs(self.d_pitch_deg), abs(self.d_roll_deg))


@dataclass(frozen=True)
class EdgeComparison:
    """Canny edges of two images compared over a mask (distances in px).

    ``a_to_b_px`` is the mean (truncated) distance from an edge pixel of the first image to
    the nearest edge of the second; ``chamfer_px`` the mean of both directions;
    ``matched_fraction`` the share of edge pixels (both ways) within 2 px of the other's.
    """

    chamfer_px: float
    a_to_b_px: float
    b_to_a_px: float
    matched_fraction: float
    edges_a: int
    edges_b: int


@dataclass(frozen=True)
class RvmComparison:
    """The capture and the synthetic frame through the ISP (``--params``)."""

    edges: EdgeComparison
    ec_scene: Any  # criteria.EcResult of the scene's labels
    ec_capture: Any  # criteria.EcResult of the pose-corrected scene's labels


@dataclass(frozen=True)
class Check:
    """One verdict check: ``value`` against ``limit`` (pass when value ≤ limit)."""

    name: str
    value: float
    limit: float
    hint: str

    @property
    def passed(self) -> bool:
        return bool(self.value <= self.limit)


@dataclass(frozen=True)
class Validation:
    """Everything :func:`validate` measured.  ``images`` holds the pictures for people
    (RGB uint8 arrays keyed by file stem); it is not part of :meth:`to_dict`."""

    scene_name: str
    capture: str
    image_size: tuple[int, int]
    landmarks: tuple[LandmarkMatch, ...]
    n_predicted: int
    rms_before_px: float
    max_before_px: float
    rms_after_px: float
    max_after_px: float
    correction: PoseCorrection
    edges_before: EdgeComparison
    edges_after: EdgeComparison | None
    rvm: RvmComparison | None
    checks: tuple[Check, ...]
    images: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def n_found(self) -> int:
        return sum(m.found_px is not None for m in self.landmarks)

    @property
    def n_inliers(self) -> int:
        return sum(m.inlier for m in self.landmarks)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    def to_dict(self) -> dict:
        """JSON-ready summary (numbers in px, mm, degrees)."""
        d = {
            "scene": self.scene_name,
            "capture": self.capture,
            "image_size": list(self.image_size),
            "passed": self.passed,
            "checks": [{**asdict(c), "passed": c.passed} for c in self.checks],
            "landmarks": {
                "predicted": self.n_predicted,
                "found": self.n_found,
                "inliers": self.n_inliers,
                "rms_before_px": self.rms_before_px,
                "max_before_px": self.max_before_px,
                "rms_after_px": self.rms_after_px,
                "max_after_px": self.max_after_px,
                "matches": [
                    {**asdict(m), "error_before_px": m.error_before_px,
                     "error_after_px": m.error_after_px}
                    for m in self.landmarks
                ],
            },
            "pose_correction": asdict(self.correction),
            "edges_before": asdict(self.edges_before),
            "edges_after": None if self.edges_after is None else asdict(self.edges_after),
        }
        if self.rvm is not None:
            d["rvm"] = {
                "edges": asdict(self.rvm.edges),
                "ec_score_scene": self.rvm.ec_scene.score,
                "ec_score_capture": self.rvm.ec_capture.score,
                "ecs": {
                    i.id: {"scene": i.as_dict(), "capture": self.rvm.ec_capture[i.id].as_dict()}
                    for i in self.rvm.ec_scene.items
                },
            }
        return d

    def summary(self) -> str:
        """A few lines for the terminal."""
        c = self.correction
        lines = [
            f"landmarks: {self.n_inliers} inliers of {self.n_found} found "
            f"({self.n_predicted} predicted visible)",
            f"landmark error: RMS {self.rms_before_px:.2f} px (max {self.max_before_px:.2f}) "
            f"with the scene's pose, RMS {self.rms_after_px:.2f} px "
            f"(max {self.max_after_px:.2f}) after the pose correction",
            "pose correction: Δposition ({:+.1f}, {:+.1f}, {:+.1f}) mm ± ({:.1f}, {:.1f}, {:.1f}); "
            "Δyaw {:+.3f}° Δpitch {:+.3f}° Δroll {:+.3f}° ± ({:.3f}, {:.3f}, {:.3f})°".format(
                *c.d_position_mm, *c.sigma_position_mm, c.d_yaw_deg, c.d_pitch_deg,
                c.d_roll_deg, *c.sigma_angles_deg),
            "corrected mount: position [{:.4f}, {:.4f}, {:.4f}] m, yaw {:.3f}°, pitch {:.3f}°, "
            "roll {:.3f}°".format(*c.position_m, c.yaw_deg, c.pitch_deg, c.roll_deg),
            f"edges: chamfer {self.edges_before.chamfer_px:.2f} px with the scene's pose"
            + ("" if self.edges_after is None else
               f", {self.edges_after.chamfer_px:.2f} px after the pose correction"),
        ]
        if self.rvm is not None:
            lines.append(
                f"RVM image: edge chamfer {self.rvm.edges.chamfer_px:.2f} px; EC score "
                f"{self.rvm.ec_scene.score:.4g} (scene) vs {self.rvm.ec_capture.score:.4g} "
                "(pose that explains the capture)")
            changed = [i.id for i in self.rvm.ec_scene.items
                       if i.enabled and i.passed != self.rvm.ec_capture[i.id].passed]
            if changed:
                lines.append("ECs whose pass/fail differs: " + ", ".join(changed))
        for chk in self.checks:
            mark = "ok  " if chk.passed else "FAIL"
            lines.append(f"{mark} {chk.name}: {chk.value:.3g} (limit {chk.limit:g})"
                         + ("" if chk.passed else f" — {chk.hint}"))
        lines.append("verdict: " + ("PASS" if self.passed else "FAIL"))
        return "\n".join(lines)


# ---------------------------------------------------------------------------- capture
def load_capture(path: str | Path, camera: FisheyeCamera | None = None) -> np.ndarray:
    """Read a capture as (H, W, 3) uint8 RGB.

    Grey images are expanded to three channels, an alpha channel is dropped, 16-bit images
    are scaled to 8 bits.

    Raises
    ------
    RvmsimError
        One line naming the file: missing, unreadable, empty or blank, or (with
        ``camera``) a size other than the camera's.
    """
    import cv2

    path = Path(path)
    if not path.is_file():
        raise RvmsimError(f"{path}: capture not found")
    try:
        data = np.fromfile(path, dtype=np.uint8)
    except OSError as err:
        raise RvmsimError(f"{path}: cannot read capture ({err.strerror or err})") from None
    if data.size == 0:
        raise RvmsimError(f"{path}: capture is an empty file")
    img = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    if img is None or img.size == 0:
        raise RvmsimError(f"{path}: cannot read capture (not an image OpenCV can decode)")
    if img.dtype == np.uint16:
        img = (img >> 8).astype(np.uint8)
    elif img.dtype != np.uint8:
        raise RvmsimError(f"{path}: capture has {img.dtype} pixels (need 8- or 16-bit)")
    if img.ndim == 2:
        img = cv2.cvtColor(img, cv2.COLOR_GRAY2RGB)
    elif img.shape[2] == 4:
        img = cv2.cvtColor(img, cv2.COLOR_BGRA2RGB)
    else:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
    h, w = img.shape[:2]
    if camera is not None and (w, h) != (camera.width, camera.height):
        raise RvmsimError(f"{path}: capture is {w}×{h} px but the scene's camera.image_size is "
                          f"{camera.width}×{camera.height} px")
    if float(img.std()) < 1.0:
        raise RvmsimError(f"{path}: capture is blank (every pixel ≈ {int(img.mean())})")
    return img


def _gray(rgb: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY).astype(np.float32)


# ---------------------------------------------------------------------------- projection
def _project(camera: FisheyeCamera, position: np.ndarray, rotation: np.ndarray,
             points: np.ndarray) -> np.ndarray:
    """Pixels of scene ``points`` for ``camera``'s lens at another pose (no FOV test)."""
    return camera.project_rays((points - position) @ rotation)[0]


def _pose(camera: FisheyeCamera, ypr0: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(position, rotation) for the correction ``x`` = (Δx, Δy, Δz m, Δyaw, Δpitch, Δroll °)."""
    return camera.position + x[:3], rotation_from_ypr(*(ypr0 + x[3:]))


def fit_pose(camera: FisheyeCamera, ypr_deg: tuple[float, float, float], points: np.ndarray,
             found_px: np.ndarray, *, robust: bool = True,
             x0: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fisheye PnP in the scene's mount parameters.

    Parameters
    ----------
    camera : FisheyeCamera
        The scene's camera (intrinsics and lens; its pose is the starting point).
    ypr_deg : (3,) float
        The scene's mount yaw, pitch, roll, degrees (``camera.rotation`` is made from them).
    points : (N, 3) float
        Scene points, metres.
    found_px : (N, 2) float
        Where they were found in the capture, px.
    robust : bool
        Soft-L1 loss with a 1 px scale (outliers weigh less); else plain least squares.
    x0 : (6,) float, optional
        Starting correction.

    Returns
    -------
    x : (6,) float
        Δx, Δy, Δz (m) and Δyaw, Δpitch, Δroll (degrees).
    residuals_px : (N,) float
        Reprojection error of each point after the correction.
    sigma : (6,) float
        One standard error of each component of ``x`` (same units).
    """
    from scipy.optimize import least_squares

    points = np.asarray(points, dtype=np.float64)
    found_px = np.asarray(found_px, dtype=np.float64)
    ypr0 = np.asarray(ypr_deg, dtype=np.float64)

    def fun(x: np.ndarray) -> np.ndarray:
        pos, rot = _pose(camera, ypr0, x)
        return (_project(camera, pos, rot, points) - found_px).ravel()

    res = least_squares(fun, np.zeros(6) if x0 is None else np.asarray(x0, dtype=np.float64),
                        x_scale=np.array([0.01, 0.01, 0.01, 0.5, 0.5, 0.5]),
                        loss="soft_l1" if robust else "linear", f_scale=1.0, method="trf",
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=200)
    r = fun(res.x)
    resid = np.hypot(r[0::2], r[1::2])
    jac = res.jac
    dof = max(1, len(r) - 6)
    try:
        cov = np.linalg.inv(jac.T @ jac) * float(r @ r) / dof
        sigma = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        sigma = np.full(6, np.inf)
    return res.x, resid, sigma


# ---------------------------------------------------------------------------- landmarks
def _spacing_px(camera: FisheyeCamera, position: np.ndarray, rotation: np.ndarray,
                corners: list[CheckerCorner]) -> np.ndarray:
    """Image distance from each corner to its nearest checker neighbour, px."""
    p = np.array([c.point for c in corners])
    a = np.array([c.axis_a for c in corners]) * np.array([[c.square_size] for c in corners])
    b = np.array([c.axis_b for c in corners]) * np.array([[c.square_size] for c in corners])
    uv = _project(camera, position, rotation, p)
    d = [np.linalg.norm(_project(camera, position, rotation, p + s) - uv, axis=1)
         for s in (a, -a, b, -b)]
    return np.min(d, axis=0)


def _usable(camera: FisheyeCamera, corners: list[CheckerCorner], labels: np.ndarray,
            uv: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """Corners seen unoccluded (by the rendered label image) and far enough from the image
    border and the edge of the lens's field."""
    h, w = labels.shape
    p = np.array([c.point for c in corners])
    cam_pts = camera.scene_to_camera(p)
    theta = np.degrees(np.arctan2(np.hypot(cam_pts[:, 0], cam_pts[:, 1]), cam_pts[:, 2]))
    ok = (spacing >= MIN_SPACING_PX) & (theta <= camera.fov_deg / 2 - 3.0)
    half = np.clip(np.round(0.45 * spacing), 4, 24).astype(int)
    for n, c in enumerate(corners):
        if not ok[n]:
            continue
        x, y = int(round(uv[n, 0])), int(round(uv[n, 1]))
        r = half[n] + 2
        if x - r < 0 or y - r < 0 or x + r >= w or y + r >= h:
            ok[n] = False
            continue
        win = labels[y - r:y + r + 1, x - r:x + r + 1]
        ok[n] = float(np.mean(win == c.label)) >= 0.97
    return ok


def _match_local(cap: np.ndarray, syn: np.ndarray, p_syn: np.ndarray, p_pred: np.ndarray,
                 spacing: float, radius: float) -> tuple[np.ndarray | None, float]:
    """Find the rendered neighbourhood of ``p_syn`` in the capture near ``p_pred``."""
    import cv2

    h, w = cap.shape
    half = int(np.clip(round(0.45 * spacing), 4, 24))
    r = int(math.ceil(radius))
    x0, y0 = int(round(p_syn[0])) - half, int(round(p_syn[1])) - half
    tmpl = syn[y0:y0 + 2 * half + 1, x0:x0 + 2 * half + 1]
    sx0 = int(round(p_pred[0])) - half - r
    sy0 = int(round(p_pred[1])) - half - r
    sx1, sy1 = sx0 + 2 * (half + r) + 1, sy0 + 2 * (half + r) + 1
    if sx0 < 0 or sy0 < 0 or sx1 > w or sy1 > h or tmpl.shape != (2 * half + 1,) * 2:
        return None, 0.0
    if float(tmpl.std()) < 1.0:
        return None, 0.0
    res = cv2.matchTemplate(cap[sy0:sy1, sx0:sx1], tmpl, cv2.TM_CCOEFF_NORMED)
    _, best, _, loc = cv2.minMaxLoc(res)
    if not np.isfinite(best) or best < MIN_NCC:
        return None, float(best) if np.isfinite(best) else 0.0
    est = np.array([p_syn[0] + sx0 + loc[0] - x0, p_syn[1] + sy0 + loc[1] - y0])
    win = int(np.clip(round(0.3 * spacing), 2, 12))
    pt = cv2.cornerSubPix(cap, est.reshape(1, 1, 2).astype(np.float32), (win, win), (-1, -1),
                          (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 50, 1e-3))
    pt = pt.reshape(2).astype(np.float64)
    if np.linalg.norm(pt - est) > max(2.0, 0.25 * spacing):
        return None, float(best)
    return pt, float(best)


def _match_board(cap_u8: np.ndarray, scene: Scene, idx: list[int], pred: np.ndarray,
                 spacing: np.ndarray,
                 radius: float) -> dict[int, np.ndarray]:
    """The board's inner corners by cv2.findChessboardCornersSB on a crop around them."""
    import cv2
    from scipy.optimize import linear_sum_assignment

    board = scene.test_site.board
    nx, ny = board.squares[0] - 1, board.squares[1] - 1
    if len(idx) != nx * ny:
        return {}
    p = pred[idx]
    s = float(np.median(spacing[idx]))
    pad = 1.5 * s + radius
    h, w = cap_u8.shape
    x0, y0 = max(0, int(p[:, 0].min() - pad)), max(0, int(p[:, 1].min() - pad))
    x1, y1 = min(w, int(p[:, 0].max() + pad) + 1), min(h, int(p[:, 1].max() + pad) + 1)
    crop = cap_u8[y0:y1, x0:x1]
    f = float(np.clip(30.0 / max(s, 1.0), 1.0, 4.0))
    if f > 1.0:
        crop = cv2.resize(crop, None, fx=f, fy=f, interpolation=cv2.INTER_CUBIC)
    flags = cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    ok, found = cv2.findChessboardCornersSB(crop, (nx, ny), flags=flags)
    if not ok or found is None or len(found) != nx * ny:
        return {}
    # Back to image pixels: crop pixel centres sit at (i + 0.5) / f - 0.5 in the original.
    found = (found.reshape(-1, 2) + 0.5) / f - 0.5 + np.array([x0, y0])
    cost = np.linalg.norm(found[:, None, :] - p[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    d = found[rows] - p[cols]
    shift = np.median(d, axis=0)
    if np.any(np.linalg.norm(d - shift, axis=1) > 0.35 * s) or np.linalg.norm(shift) > radius + 2:
        return {}
    return {idx[c]: found[r] for r, c in zip(rows, cols)}


def find_landmarks(capture: np.ndarray, synthetic: FisheyeImages, scene: Scene,
                   corners: list[CheckerCorner], *, position: np.ndarray,
                   rotation: np.ndarray, radius_px: float,
                   usable: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray]:
    """Find ``corners`` in the capture, predicted from the pose (position, rotation).

    Returns
    -------
    found : (N, 2) float
        Capture pixels (NaN where not found).
    ncc : (N,) float
    method : list of str
    predicted : (N, 2) float
        The predictions searched around.
    """
    cam = synthetic.camera
    pts = np.array([c.point for c in corners])
    pred = _project(cam, position, rotation, pts)
    syn_uv = _project(cam, cam.position, cam.rotation, pts)
    spacing = _spacing_px(cam, position, rotation, corners)
    cap_g = _gray(capture)
    syn_g = _gray(synthetic.color)
    found = np.full((len(corners), 2), np.nan)
    ncc = np.zeros(len(corners))
    method = [""] * len(corners)
    board_idx = [n for n, c in enumerate(corners)
                 if c.label == L.BOARD and c.name.startswith("board_inner")]
    if board_idx and all(usable[n] for n in board_idx):
        for n, xy in _match_board(cap_g.astype(np.uint8), scene, board_idx, pred,
                                  spacing, radius_px).items():
            found[n], ncc[n], method[n] = xy, 1.0, "chessboard"
    for n in range(len(corners)):
        if not usable[n] or method[n]:
            continue
        r = min(radius_px, 0.6 * spacing[n])
        xy, score = _match_local(cap_g, syn_g, syn_uv[n], pred[n], spacing[n], r)
        ncc[n] = score
        if xy is not None:
            found[n], method[n] = xy, "local"
    return found, ncc, method, pred


# ---------------------------------------------------------------------------- edges
def _edges(rgb: np.ndarray, mask: np.ndarray) -> np.ndarray:
    import cv2

    g = _gray(rgb)
    vals = g[mask]
    lo, hi = (np.percentile(vals, (2, 98)) if vals.size else (0.0, 255.0))
    g = np.clip((g - lo) * (255.0 / max(hi - lo, 1.0)), 0, 255).astype(np.uint8)
    g = cv2.GaussianBlur(g, (0, 0), 1.0)
    e = cv2.Canny(g, 40, 100, L2gradient=True) > 0
    return e & mask


def compare_edges(a: np.ndarray, b: np.ndarray, mask: np.ndarray) -> tuple[EdgeComparison,
                                                                            np.ndarray, np.ndarray]:
    """Symmetric chamfer distance between the Canny edges of two RGB images over ``mask``.

    Returns
    -------
    comparison : EdgeComparison
    edges_a, edges_b : (H, W) bool
        The edge maps, for drawing.
    """
    import cv2

    ea, eb = _edges(a, mask), _edges(b, mask)

    def dist_to(e: np.ndarray) -> np.ndarray:
        if not e.any():
            return np.full(e.shape, CHAMFER_TRUNCATE_PX, np.float32)
        return cv2.distanceTransform((~e).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)

    da, db = dist_to(ea), dist_to(eb)
    ab = np.minimum(db[ea], CHAMFER_TRUNCATE_PX)
    ba = np.minimum(da[eb], CHAMFER_TRUNCATE_PX)
    m_ab = float(ab.mean()) if ab.size else CHAMFER_TRUNCATE_PX
    m_ba = float(ba.mean()) if ba.size else CHAMFER_TRUNCATE_PX
    within = (np.count_nonzero(ab <= 2.0) + np.count_nonzero(ba <= 2.0)) / max(1, ab.size + ba.size)
    return (EdgeComparison((m_ab + m_ba) / 2, m_ab, m_ba, float(within), int(ab.size),
                           int(ba.size)), ea, eb)


def _model_mask(labels: np.ndarray) -> np.ndarray:
    """Where the scene models the world: not void, not sky, eroded by 4 px."""
    import cv2

    m = ((labels != L.VOID) & (labels != L.SKY)).astype(np.uint8)
    return cv2.erode(m, np.ones((9, 9), np.uint8)) > 0


# ---------------------------------------------------------------------------- pictures
def _edge_overlay(capture: np.ndarray, e_cap: np.ndarray, e_syn: np.ndarray) -> np.ndarray:
    """Capture (dimmed grey), its edges green, the scene's edges magenta, both white."""
    g = (_gray(capture) * 0.45).astype(np.uint8)
    out = np.repeat(g[..., None], 3, axis=2)
    out[e_cap] = (40, 230, 40)
    out[e_syn] = (255, 40, 255)
    out[e_cap & e_syn] = (255, 255, 255)
    return out


def _landmark_picture(capture: np.ndarray, matches: tuple[LandmarkMatch, ...]) -> np.ndarray:
    """Predicted (red +), found (green o), outliers (orange x), corrected (cyan dot); the
    red line from prediction to find is drawn 5× longer so small errors show."""
    import cv2

    out = capture.copy()
    for m in matches:
        p = np.array(m.predicted_px)
        if m.found_px is None:
            cv2.drawMarker(out, tuple(int(round(v)) for v in p), (255, 60, 60),
                           cv2.MARKER_CROSS, 6, 1)
            continue
        f = np.array(m.found_px)
        tip = f + 4.0 * (f - p)
        cv2.line(out, tuple(int(round(v)) for v in p), tuple(int(round(v)) for v in tip),
                 (255, 60, 60), 1, cv2.LINE_AA)
        if m.inlier:
            cv2.circle(out, tuple(int(round(v)) for v in f), 4, (40, 230, 40), 1, cv2.LINE_AA)
            cv2.circle(out, tuple(int(round(v)) for v in m.corrected_px), 1, (0, 220, 255), -1)
        else:
            cv2.drawMarker(out, tuple(int(round(v)) for v in f), (255, 150, 0),
                           cv2.MARKER_TILTED_CROSS, 9, 2)
    return out


def _blend(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return ((a.astype(np.uint16) + b.astype(np.uint16)) // 2).astype(np.uint8)


# ---------------------------------------------------------------------------- pose search
@dataclass
class _Fit:
    x: np.ndarray
    found: np.ndarray
    ncc: np.ndarray
    method: list
    inliers: np.ndarray
    sigma: np.ndarray


def _match_and_fit(capture: np.ndarray, synthetic: FisheyeImages, scene: Scene,
                   corners: list[CheckerCorner], ypr0: np.ndarray, x: np.ndarray,
                   usable: np.ndarray, *, search_px: float, need: int, capture_name: str,
                   n_predicted: int) -> _Fit:
    """Alternate landmark matching and pose fitting three times, the search radius
    shrinking to 3× the last RMS."""
    cam = synthetic.camera
    pts = np.array([c.point for c in corners])
    radius = float(search_px)
    for _ in range(3):
        pos, rot = _pose(cam, ypr0, x)
        found, ncc, method, _pred = find_landmarks(capture, synthetic, scene, corners,
                                                   position=pos, rotation=rot,
                                                   radius_px=radius, usable=usable)
        ok = np.isfinite(found[:, 0])
        if ok.sum() < need:
            raise RvmsimError(
                f"{capture_name}: too few landmarks found: {int(ok.sum())} of {n_predicted} "
                f"predicted checker corners (need {need}); is this a capture of this scene, "
                f"and is the pose within ~{search_px:g} px (--search-px)?")
        idx = np.flatnonzero(ok)
        x_r, res_r, _ = fit_pose(cam, ypr0, pts[idx], found[idx], robust=True, x0=x)
        mad = float(np.median(res_r)) * 1.4826
        keep = res_r <= max(1.0, 3.0 * mad)
        if keep.sum() < need:
            keep = res_r <= np.sort(res_r)[need - 1]
        x, res_i, sigma = fit_pose(cam, ypr0, pts[idx[keep]], found[idx[keep]], robust=False,
                                   x0=x_r)
        inl = np.zeros(len(corners), bool)
        inl[idx[keep]] = True
        rms = float(np.sqrt(np.mean(res_i ** 2)))
        radius = float(np.clip(3.0 * rms, 2.0, search_px))
    return _Fit(x, found, ncc, method, inl, sigma)


class _ShadeScorer:
    """How well the ground patterns' black and white, seen from a pose, explain the capture:
    the correlation of the pattern's shade (0 black, 1 white) with the capture's grey level
    over every 2nd pixel where the synthetic frame sees the ground."""

    def __init__(self, scene: Scene, cam: FisheyeCamera, labels: np.ndarray,
                 capture: np.ndarray):
        vv, uu = np.mgrid[0:cam.height:2, 0:cam.width:2]
        keep = np.isin(labels[vv, uu], (L.GROUND, L.GROUND_PATTERN))
        uv = np.stack([uu[keep], vv[keep]], axis=1).astype(np.float64)
        self.rays, in_fov = cam.pixel_rays(uv)
        self.rays = self.rays[in_fov]
        self.grey = _gray(capture)[vv[keep], uu[keep]][in_fov].astype(np.float64)
        self.patterns = scene.test_site.ground_patterns

    def shifts(self) -> list[np.ndarray]:
        """Camera moves that map the first pattern's checker onto itself with the same
        polarity: (du, dv) squares, du + dv even, up to two squares each way."""
        p = self.patterns[0]
        ax, bx = pattern_axes(p)
        return [p.square_size * (du * ax + dv * bx)
                for du in range(-2, 3) for dv in range(-2, 3)
                if (du + dv) % 2 == 0 and (du, dv) != (0, 0)]

    def __call__(self, position: np.ndarray, rotation: np.ndarray) -> float:
        d = self.rays @ rotation.T
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (-PATTERN_LIFT_M - position[1]) / d[:, 1]
        hit = (d[:, 1] > 1e-6) & (t > 0)
        x = position[0] + t * d[:, 0]
        z = position[2] + t * d[:, 2]
        shade = np.full(len(d), np.nan)
        for p in self.patterns:
            sh = pattern_shade(p, x, z)
            shade = np.where(np.isnan(shade), sh, shade)
        ok = hit & np.isfinite(shade)
        if ok.sum() < 100 or np.ptp(shade[ok]) == 0:
            return -1.0
        return float(np.corrcoef(shade[ok], self.grey[ok])[0, 1])


def _dense_align(shade: _ShadeScorer, cam: FisheyeCamera, ypr0: np.ndarray) -> np.ndarray:
    """Nelder-Mead over the pose correction maximising the shade correlation, from zero
    (steps of 30 mm and 1°); zero if that does not improve it."""
    from scipy.optimize import minimize

    def cost(x: np.ndarray) -> float:
        return -shade(*_pose(cam, ypr0, x))

    x0 = np.zeros(6)
    steps = np.array([0.03, 0.03, 0.03, 1.0, 1.0, 1.0])
    simplex = np.vstack([x0, x0 + np.diag(steps)])
    res = minimize(cost, x0, method="Nelder-Mead",
                   options={"initial_simplex": simplex, "xatol": 1e-4, "fatol": 1e-5,
                            "maxfev": 800})
    return res.x if res.fun < cost(x0) else x0


# ---------------------------------------------------------------------------- main
def validate(
    scene: Scene,
    capture: np.ndarray,
    *,
    synthetic: FisheyeImages | None = None,
    scene_file: str | Path | None = None,
    capture_name: str = "<array>",
    params: Any = None,
    output: Any = None,
    criteria: Any = None,
    tolerances: Tolerances = Tolerances(),
    search_px: float = 30.0,
    rerender: bool = True,
    progress: bool = False,
) -> Validation:
    """Compare a real capture with the scene's synthetic frame.

    Parameters
    ----------
    scene : Scene
    capture : (H, W, 3) uint8
        RGB capture of the physical camera (see :func:`load_capture`).
    synthetic : FisheyeImages, optional
        The scene's rendered frame; rendered (through the render cache when ``scene_file``
        is given) when missing.
    scene_file : path, optional
        The scene's file, for the render cache.
    capture_name : str
        For messages and the JSON summary.
    params : IspParams, optional
        With ISP parameters, the capture and the synthetic frame are also compared as RVM
        images, and the ECs evaluated on both.
    output : OutputSpec, optional
        RVM image size (with ``params``).
    criteria : Criteria, optional
        EC definitions (with ``params``); default: the paper's.
    tolerances : Tolerances
        The verdict's limits.
    search_px : float
        How far from its prediction a landmark is searched for at first, px.
    rerender : bool
        Render the scene again at the corrected pose (for the corrected overlay, the
        edge comparison after correction and the capture's ECs).
    progress : bool
        Progress bars while rendering.

    Raises
    ------
    RvmsimError
        Capture of the wrong size, or fewer than ``tolerances.min_landmarks`` landmarks found.
    """
    from ..render import render_fisheye

    if synthetic is None:
        if scene_file is not None:
            from ..render import cached_render

            synthetic = cached_render(scene, progress=progress)[0]
        else:
            synthetic = render_fisheye(scene, progress=progress)
    cam = synthetic.camera
    if capture.shape[:2] != (cam.height, cam.width) or capture.ndim != 3:
        raise RvmsimError(f"{capture_name}: capture is {capture.shape[1]}×{capture.shape[0]} px "
                          f"but the scene's camera is {cam.width}×{cam.height} px")
    m = scene.camera.mount
    ypr0 = np.array([m.yaw_deg, m.pitch_deg, m.roll_deg], dtype=np.float64)

    corners = checker_corners(scene)
    if not corners:
        raise RvmsimError(f"{scene.source}: the scene has no checker landmarks (enable "
                          "test_site.board or add test_site.ground_patterns)")
    pts = np.array([c.point for c in corners])
    syn_uv = _project(cam, cam.position, cam.rotation, pts)
    spacing0 = _spacing_px(cam, cam.position, cam.rotation, corners)
    usable = _usable(cam, corners, synthetic.labels, syn_uv, spacing0)
    n_predicted = int(usable.sum())
    need = tolerances.min_landmarks
    if n_predicted < need:
        raise RvmsimError(f"{scene.source}: only {n_predicted} checker corners are visible in "
                          f"the synthetic frame (need {need})")

    def match_and_fit(x: np.ndarray) -> _Fit:
        return _match_and_fit(capture, synthetic, scene, corners, ypr0, x, usable,
                              search_px=search_px, need=need, capture_name=capture_name,
                              n_predicted=n_predicted)

    if not scene.test_site.ground_patterns:
        fit = match_and_fit(np.zeros(6))
    else:
        # Dense pre-alignment: the pose whose ground-pattern shade best fits the capture
        # brings the corners within a few px even when the scene's pose is tens of px off.
        shade = _ShadeScorer(scene, cam, synthetic.labels, capture)
        fit = match_and_fit(_dense_align(shade, cam, ypr0))
        # A checker is periodic: a pose one square off diagonally matches every corner with
        # the right polarity.  The patterns' non-periodic parts (borders, white squares,
        # discs) decide: try the shifts, keep the pose whose ground shade fits the capture.
        score = shade(*_pose(cam, ypr0, fit.x))
        for dx in shade.shifts():
            x_try = fit.x.copy()
            x_try[:3] += dx
            if shade(*_pose(cam, ypr0, x_try)) <= score + 0.02:
                continue
            try:
                alt = match_and_fit(x_try)
            except RvmsimError:
                continue
            alt_score = shade(*_pose(cam, ypr0, alt.x))
            if alt_score > score + 0.02:
                fit, score = alt, alt_score
    x, found, ncc, method, inl, sigma = fit.x, fit.found, fit.ncc, fit.method, fit.inliers, fit.sigma

    pos1, rot1 = _pose(cam, ypr0, x)
    corr_uv = _project(cam, pos1, rot1, pts)
    err_before = np.linalg.norm(found[inl] - syn_uv[inl], axis=1)
    err_after = np.linalg.norm(found[inl] - corr_uv[inl], axis=1)
    matches = tuple(
        LandmarkMatch(
            name=c.name, point=c.point,
            predicted_px=(float(syn_uv[n, 0]), float(syn_uv[n, 1])),
            found_px=None if not np.isfinite(found[n, 0]) else (float(found[n, 0]),
                                                                float(found[n, 1])),
            corrected_px=(float(corr_uv[n, 0]), float(corr_uv[n, 1])),
            method=method[n], ncc=float(ncc[n]), inlier=bool(inl[n]),
        )
        for n, c in enumerate(corners) if usable[n]
    )
    ypr1 = ypr0 + x[3:]
    correction = PoseCorrection(
        d_position_mm=tuple(float(v) * 1000 for v in x[:3]),
        d_yaw_deg=float(x[3]), d_pitch_deg=float(x[4]), d_roll_deg=float(x[5]),
        sigma_position_mm=tuple(float(v) * 1000 for v in sigma[:3]),
        sigma_angles_deg=tuple(float(v) for v in sigma[3:]),
        position_m=tuple(float(v) for v in pos1),
        yaw_deg=float(ypr1[0]), pitch_deg=float(ypr1[1]), roll_deg=float(ypr1[2]),
    )

    # Edges, pictures, and the pose-corrected frame.
    mask = _model_mask(synthetic.labels)
    edges_before, e_cap, e_syn = compare_edges(capture, synthetic.color, mask)
    images = {
        "overlay": _blend(capture, synthetic.color),
        "edges": _edge_overlay(capture, e_cap, e_syn),
        "landmarks": _landmark_picture(capture, matches),
    }
    corrected = None
    edges_after = None
    if rerender:
        corrected_scene = scene_with_mount(scene, correction)
        corrected = render_fisheye(corrected_scene, camera=replace(cam, position=pos1,
                                                                   rotation=rot1),
                                   progress=progress)
        mask1 = _model_mask(corrected.labels)
        edges_after, e_cap1, e_syn1 = compare_edges(capture, corrected.color, mask1)
        images["overlay_corrected"] = _blend(capture, corrected.color)
        images["edges_corrected"] = _edge_overlay(capture, e_cap1, e_syn1)

    rvm = None
    if params is not None:
        rvm, rvm_images = _compare_rvm(capture, synthetic, corrected, params, output, criteria)
        images.update(rvm_images)

    rms_after = float(np.sqrt(np.mean(err_after ** 2)))
    checks = [
        Check("landmark_rms_after_correction_px", rms_after, tolerances.max_rms_px,
              "the corrected pose still leaves the landmarks off: check the intrinsics, the "
              "lens (k1..k4, fov) and the pattern layout against the capture"),
        Check("pose_position_correction_mm", correction.d_position_norm_mm,
              tolerances.max_position_mm,
              "the camera's mount position is off: write the corrected scene (--write-scene)"),
        Check("pose_angle_correction_deg", correction.max_d_angle_deg, tolerances.max_angle_deg,
              "the camera's mount angles are off: write the corrected scene (--write-scene)"),
    ]
    if tolerances.max_chamfer_px is not None:
        checks.append(Check("edge_chamfer_px", edges_before.chamfer_px, tolerances.max_chamfer_px,
                            "edges differ: compare the edge overlay for parts the scene "
                            "lacks or misplaces"))
    return Validation(
        scene_name=scene.name, capture=capture_name, image_size=(cam.width, cam.height),
        landmarks=matches, n_predicted=n_predicted,
        rms_before_px=float(np.sqrt(np.mean(err_before ** 2))),
        max_before_px=float(err_before.max()),
        rms_after_px=rms_after,
        max_after_px=float(err_after.max()),
        correction=correction, edges_before=edges_before, edges_after=edges_after, rvm=rvm,
        checks=tuple(checks), images=images,
    )


def scene_with_mount(scene: Scene, correction: PoseCorrection) -> Scene:
    """A copy of ``scene`` with the corrected mount pose."""
    mount = scene.camera.mount.model_copy(update={
        "position": correction.position_m, "yaw_deg": correction.yaw_deg,
        "pitch_deg": correction.pitch_deg, "roll_deg": correction.roll_deg})
    camera = scene.camera.model_copy(update={"mount": mount})
    return scene.model_copy(update={"camera": camera})


def _compare_rvm(capture: np.ndarray, synthetic: FisheyeImages,
                 corrected: FisheyeImages | None, params: Any, output: Any,
                 criteria: Any) -> tuple[RvmComparison, dict]:
    from ..criteria.core import evaluate
    from ..isp import OutputSpec, process

    output = output or OutputSpec()
    rvm_cap, _ = process(capture, None, params, output)
    rvm_syn, lab_syn = process(synthetic.color, synthetic.labels, params, output)
    lab_cap = lab_syn if corrected is None else process(None, corrected.labels, params, output)[1]
    mask = _model_mask(lab_syn)
    edges, e_cap, e_syn = compare_edges(rvm_cap, rvm_syn, mask)
    ec_scene = evaluate(lab_syn, criteria)
    ec_capture = evaluate(lab_cap, criteria)
    images = {
        "rvm_capture": rvm_cap,
        "rvm_synthetic": rvm_syn,
        "rvm_overlay": _blend(rvm_cap, rvm_syn),
        "rvm_edges": _edge_overlay(rvm_cap, e_cap, e_syn),
    }
    return RvmComparison(edges, ec_scene, ec_capture), images


# ---------------------------------------------------------------------------- files
def write_outputs(result: Validation, out_dir: str | Path) -> list[Path]:
    """Write ``validation.json``, the PNGs and ``validation.html`` into ``out_dir``."""
    from .._io import write_png

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RvmsimError(f"{out}: cannot create output folder ({err.strerror or err})") from None
    paths = [write_png(out / f"{name}.png", img) for name, img in result.images.items()]
    js = out / "validation.json"
    try:
        js.write_text(json.dumps(result.to_dict(), indent=2, default=json_default) + "\n")
        html_path = out / "validation.html"
        html_path.write_text(_html(result))
    except OSError as err:
        raise RvmsimError(f"{out}: cannot write results ({err.strerror or err})") from None
    return [js, html_path, *paths]


def _html(result: Validation) -> str:
    """One self-contained page: verdict, numbers, pictures (PNG data URIs)."""
    from ..report.page import escape, img_tag, page

    c = result.correction
    rows = "".join(
        f'<tr class="{"pass" if k.passed else "fail"}"><td>{escape(k.name)}</td>'
        f"<td>{k.value:.3g}</td><td>≤ {k.limit:g}</td><td>{'pass' if k.passed else 'FAIL'}"
        f"</td><td>{'' if k.passed else escape(k.hint)}</td></tr>"
        for k in result.checks
    )
    pose = "".join(
        f"<tr><td>{escape(n)}</td><td>{v:+.2f}</td><td>± {s:.2f}</td><td>{escape(u)}</td></tr>"
        for n, v, s, u in (
            ("Δx (driver side)", c.d_position_mm[0], c.sigma_position_mm[0], "mm"),
            ("Δy (down)", c.d_position_mm[1], c.sigma_position_mm[1], "mm"),
            ("Δz (rearward)", c.d_position_mm[2], c.sigma_position_mm[2], "mm"),
            ("Δyaw", c.d_yaw_deg, c.sigma_angles_deg[0], "°"),
            ("Δpitch", c.d_pitch_deg, c.sigma_angles_deg[1], "°"),
            ("Δroll", c.d_roll_deg, c.sigma_angles_deg[2], "°"),
        )
    )
    captions = {
        "landmarks": "Landmarks: predicted from the scene (red +, error line drawn 5× long), "
                     "found (green o), outliers (orange x), after correction (cyan dot)",
        "overlay": "Capture and synthetic frame blended (scene's pose)",
        "overlay_corrected": "Capture and synthetic frame blended (corrected pose)",
        "edges": "Edges: capture green, synthetic magenta, both white (scene's pose)",
        "edges_corrected": "Edges after the pose correction",
        "rvm_capture": "Capture through the ISP",
        "rvm_synthetic": "Synthetic frame through the ISP",
        "rvm_overlay": "RVM images blended",
        "rvm_edges": "RVM edges: capture green, synthetic magenta",
    }
    figs = "".join(
        f"<figure>{img_tag(img, name, 960)}<figcaption>{escape(captions.get(name, name))}"
        "</figcaption></figure>"
        for name, img in result.images.items()
    )
    verdict = "PASS" if result.passed else "FAIL"
    summary = escape(result.summary())
    return page(f"Validation: {result.scene_name}", f"""
<h1>Validation of {escape(result.scene_name)}: {verdict}</h1>
<p>Capture: {escape(result.capture)}, {result.image_size[0]}×{result.image_size[1]} px.
{result.n_inliers} landmarks matched ({result.n_found} found,
{result.n_predicted} predicted visible).</p>
<h2>Verdict</h2><table><tr><th>check</th><th>value</th><th>limit</th><th></th>
<th>what to fix</th></tr>{rows}</table>
<h2>Pose correction</h2><table><tr><th></th><th>change</th><th>σ</th><th></th></tr>{pose}
</table>
<pre>{summary}</pre>
<h2>Pictures</h2>{figs}
""")


_MOUNT_KEYS = ("position", "yaw_deg", "pitch_deg", "roll_deg")


def write_corrected_scene(scene_file: str | Path, correction: PoseCorrection,
                          out_file: str | Path) -> Path:
    """Copy ``scene_file`` to ``out_file`` with the corrected mount pose.

    Only the ``camera.mount`` values change; comments and layout stay.  Mesh paths stay
    valid when ``out_file`` is in another folder only if they are absolute, so the file is
    checked by loading it again.

    Raises
    ------
    RvmsimError
        When the mount cannot be rewritten in place or the result does not load.
    """
    from .._io import key_lines, read_text
    from ..errors import SceneError
    from ..scene import load_scene

    scene_file, out_file = Path(scene_file), Path(out_file)
    text = read_text(scene_file, SceneError)
    lines = text.splitlines(keepends=True)
    where = key_lines(text)
    values = {
        "position": "[{:.4f}, {:.4f}, {:.4f}]".format(*correction.position_m),
        "yaw_deg": f"{correction.yaw_deg:.3f}",
        "pitch_deg": f"{correction.pitch_deg:.3f}",
        "roll_deg": f"{correction.roll_deg:.3f}",
    }
    pos_line = where.get(("camera", "mount", "position"))
    if pos_line is None:
        raise RvmsimError(f"{scene_file}: camera.mount.position: not found")
    indent = re.match(r"\s*", lines[pos_line - 1]).group(0)
    inserts = []
    drop: set[int] = set()
    for key in _MOUNT_KEYS:
        ln = where.get(("camera", "mount", key))
        if ln is None:
            inserts.append(f"{indent}{key}: {values[key]}\n")
            continue
        line = lines[ln - 1]
        mt = re.match(rf"^([ \t]*{key}[ \t]*:[ \t]*)([^#\r\n]*?)([ \t]*(#[^\r\n]*)?)(\r?\n)?$",
                      line)
        ok = mt is not None
        if ok and key == "position" and "]" not in mt.group(2):
            # A block list (one "- x" line per item) becomes one flow list.
            items = [where.get(("camera", "mount", "position", i)) for i in range(3)]
            ok = mt.group(2) == "" and all(items) and all(
                re.match(r"^[ \t]*-[ \t]*[-+.\deE]+[ \t]*(#.*)?\r?\n?$", lines[i - 1])
                for i in items)
            if ok:
                drop.update(i - 1 for i in items)
        if not ok:
            raise RvmsimError(f"{scene_file}:{ln}: camera.mount.{key}: cannot rewrite this "
                              "value in place (write it as a plain number, the position as "
                              "[x, y, z])")
        head = mt.group(1) if mt.group(1).endswith((" ", "\t")) else mt.group(1) + " "
        lines[ln - 1] = head + values[key] + (mt.group(3) or "") + (mt.group(5) or "\n")
    if inserts:
        lines[pos_line:pos_line] = inserts
        drop = {i + len(inserts) if i >= pos_line else i for i in drop}
    lines = [ln for i, ln in enumerate(lines) if i not in drop]
    new_text = "".join(lines)
    try:
        out_file.parent.mkdir(parents=True, exist_ok=True)
        out_file.write_text(new_text)
    except OSError as err:
        raise RvmsimError(f"{out_file}: cannot write scene ({err.strerror or err})") from None
    load_scene(out_file)
    return out_file
