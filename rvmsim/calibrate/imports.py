"""Existing calibrations read into a Kannala-Brandt camera: OpenCV FileStorage YAML
(``camera_matrix``, ``dist_coeffs``), a Kalibr camchain (pinhole-equidistant), an
OCamCalib / Scaramuzza ``calib_results.txt`` (fitted to Kannala-Brandt, with the fit error
in px), or a scene's camera block (as :func:`rvmsim.calibrate.camera_block` writes it)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .board import CalibrationInputError

__all__ = ["ImportedCamera", "import_calibration", "fit_kannala_brandt"]


@dataclass(frozen=True)
class ImportedCamera:
    """K (3, 3), D (4,) (cv2.fisheye), image size (width, height) px or None, the source
    format, and for fitted models the fit's RMS and largest error (px; 0 when exact)."""

    K: np.ndarray
    D: np.ndarray
    image_size: tuple[int, int] | None
    source_format: str
    fit_rms_px: float = 0.0
    fit_max_px: float = 0.0


def _err(path: Path, key: str, msg: str) -> CalibrationInputError:
    return CalibrationInputError(str(path), key, msg)


def _floats(path: Path, key: str, value: object, n: int) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise _err(path, key, f"expected {n} numbers") from None
    if a.size != n or not np.all(np.isfinite(a)):
        raise _err(path, key, f"expected {n} finite numbers, got {a.size}")
    return a


def _cv2_message(err: Exception) -> str:
    """The last line of a cv2.error (its "error: (-215:…) …" part)."""
    text = str(err).strip().splitlines()[-1] if str(err).strip() else type(err).__name__
    return text.split(" error: ")[-1][:160]


def _opencv(path: Path) -> ImportedCamera:
    import cv2

    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except cv2.error as err:
        raise _err(path, "", f"not an OpenCV FileStorage file: {_cv2_message(err)}") from None
    mats = {}
    try:
        for key in ("camera_matrix", "dist_coeffs", "resolution"):
            node = fs.getNode(key)
            mats[key] = None if node.empty() else node.mat()
            if not node.empty() and mats[key] is None:
                raise _err(path, key, "expected an !!opencv-matrix (rows, cols, dt, data)")
    except cv2.error as err:
        raise _err(path, key, f"unreadable: {_cv2_message(err)}") from None
    finally:
        fs.release()
    K, D, res = mats["camera_matrix"], mats["dist_coeffs"], mats["resolution"]
    if K is None:
        raise _err(path, "camera_matrix", "missing (OpenCV FileStorage)")
    if D is None:
        raise _err(path, "dist_coeffs", "missing (OpenCV FileStorage)")
    k = _floats(path, "camera_matrix", K, 9).reshape(3, 3)
    d = _floats(path, "dist_coeffs", D, 4)
    size = None if res is None else tuple(int(x) for x in np.ravel(res)[:2])
    return ImportedCamera(k, d, size, "opencv")  # type: ignore[arg-type]


def _kalibr(path: Path, doc: dict[Any, Any]) -> ImportedCamera:
    name = sorted(k for k in doc if str(k).startswith("cam"))[0]
    cam = doc[name]
    if not isinstance(cam, dict):
        raise _err(path, name, "expected a mapping")
    model, dist = cam.get("camera_model"), cam.get("distortion_model")
    if model != "pinhole" or dist != "equidistant":
        raise _err(path, f"{name}.camera_model",
                   f"only pinhole-equidistant is supported (got {model}-{dist})")
    fu, fv, pu, pv = _floats(path, f"{name}.intrinsics", cam.get("intrinsics"), 4)
    d = _floats(path, f"{name}.distortion_coeffs", cam.get("distortion_coeffs"), 4)
    res = cam.get("resolution")
    size = None if res is None else tuple(int(x) for x in _floats(path, f"{name}.resolution",
                                                                  res, 2))
    K = np.array([[fu, 0, pu], [0, fv, pv], [0, 0, 1.0]])
    return ImportedCamera(K, d, size, "kalibr")  # type: ignore[arg-type]


def _camera_block(path: Path, doc: dict[Any, Any]) -> ImportedCamera:
    cam = doc.get("camera", doc)
    try:
        K = np.asarray(cam["intrinsics"]["K"], np.float64)
        d = _floats(path, "camera.lens.k", cam["lens"]["k"], 4)
        size = tuple(int(x) for x in cam["image_size"])
    except (KeyError, TypeError, ValueError):
        raise _err(path, "camera", "expected image_size, intrinsics.K and lens.k") from None
    return ImportedCamera(_floats(path, "camera.intrinsics.K", K, 9).reshape(3, 3), d,
                          size, "scene")  # type: ignore[arg-type]


def _ocam_numbers(path: Path, text: str) -> list[list[float]]:
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            rows.append([float(x) for x in line.split()])
        except ValueError:
            raise _err(path, "", f"not a number in line {line[:40]!r} (OCamCalib)") from None
    if (len(rows) < 5 or len(rows[0]) < 2 or int(rows[0][0]) != len(rows[0]) - 1
            or len(rows[2]) < 2 or len(rows[3]) < 3 or len(rows[4]) < 2):
        raise _err(path, "", "expected the OCamCalib calib_results.txt layout (polynomial, "
                             "inverse polynomial, centre, affine c d e, height width)")
    c, d, e = rows[3][:3]
    if not (1 <= rows[4][0] <= 100000 and 1 <= rows[4][1] <= 100000) or abs(c - d * e) < 1e-12:
        raise _err(path, "", "OCamCalib: image size must be 1..100000 px and the affine "
                             "matrix [c d; e 1] invertible")
    if not all(np.isfinite(x) for r in rows for x in r):
        raise _err(path, "", "OCamCalib: every number must be finite")
    return rows


def _ocam(path: Path, text: str) -> ImportedCamera:
    rows = _ocam_numbers(path, text)
    poly = np.array(rows[0][1:])
    xc, yc = rows[2][:2]  # row, column of the distortion centre
    c, d, e = rows[3][:3]
    h, w = int(rows[4][0]), int(rows[4][1])
    # Rays of a grid of pixels (cam2world), then Kannala-Brandt fitted to them.
    grid_c, grid_r = np.meshgrid(np.linspace(0, w - 1, 41), np.linspace(0, h - 1, 31))
    col, row = grid_c.ravel(), grid_r.ravel()
    inv = 1.0 / (c - d * e)
    xp = inv * ((row - xc) - d * (col - yc))
    yp = inv * (-e * (row - xc) + c * (col - yc))
    rho = np.hypot(xp, yp)
    z = np.polyval(poly[::-1], rho)
    theta = np.arctan2(rho, -z)
    keep = (theta < np.radians(100)) & (rho > 1e-9)
    with np.errstate(invalid="ignore", divide="ignore"):
        dirs = np.stack([yp / rho, xp / rho], axis=1)  # (column, row) unit direction
    pix = np.stack([col, row], axis=1)
    K, D, rms, mx = fit_kannala_brandt(theta[keep], dirs[keep], pix[keep], (w, h))
    return ImportedCamera(K, D, (w, h), "ocamcalib", rms, mx)


def fit_kannala_brandt(theta: np.ndarray, dirs: np.ndarray, pixels: np.ndarray,
                       size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray, float, float]:
    """K, D of the Kannala-Brandt camera that best maps rays to ``pixels``.

    Parameters
    ----------
    theta : (N,) float
        Incidence angles, radians.
    dirs : (N, 2) float
        Unit image-plane directions of the rays (x right, y down).
    pixels : (N, 2) float
        The pixels (x, y) those rays hit, px.
    size : (int, int)
        (width, height) px, for the start.

    Returns
    -------
    K (3, 3), D (4,), RMS and largest pixel error of the fit (px).
    """
    from scipy.optimize import least_squares

    def model(p: np.ndarray) -> np.ndarray:
        fx, fy, cx, cy, k1, k2, k3, k4 = p
        t2 = theta**2
        td = theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))))
        return np.stack([fx * td * dirs[:, 0] + cx, fy * td * dirs[:, 1] + cy], axis=1)

    r = np.linalg.norm(pixels - np.array([(size[0] - 1) / 2, (size[1] - 1) / 2]), axis=1)
    f0 = float(np.median(r[theta > 0.1] / theta[theta > 0.1])) if np.any(theta > 0.1) else size[0] / np.pi
    p0 = np.array([f0, f0, (size[0] - 1) / 2, (size[1] - 1) / 2, 0, 0, 0, 0])
    sol = least_squares(lambda p: (model(p) - pixels).ravel(), p0, method="lm", max_nfev=5000)
    err = np.linalg.norm(model(sol.x) - pixels, axis=1)
    fx, fy, cx, cy = sol.x[:4]
    K = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    return K, sol.x[4:].copy(), float(np.sqrt(np.mean(err**2))), float(err.max())


def import_calibration(path: str | Path) -> ImportedCamera:
    """Read a calibration file (format by its content: OpenCV FileStorage, Kalibr camchain,
    OCamCalib ``calib_results.txt``, or a scene / camera block YAML).

    Raises
    ------
    CalibrationInputError
        One line naming the file (and the key) when it is unreadable or of no known format.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8", errors="replace")
    except OSError as err:
        raise _err(p, "", f"cannot read: {err.strerror or err}") from None
    if text.lstrip().startswith("%YAML") or "camera_matrix" in text:
        return _opencv(p)
    if text.lstrip().startswith("#") and "polynomial" in text.lower():
        return _ocam(p, text)
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise _err(p, "", f"malformed YAML: {str(err).splitlines()[0]}") from None
    if isinstance(doc, dict) and any(str(k).startswith("cam") and isinstance(v, dict)
                                     and "camera_model" in v for k, v in doc.items()):
        return _kalibr(p, doc)
    if isinstance(doc, dict) and ("camera" in doc or "intrinsics" in doc):
        return _camera_block(p, doc)
    raise _err(p, "", "not a known calibration format (OpenCV FileStorage YAML, Kalibr "
                      "camchain, OCamCalib calib_results.txt, scene camera block)")
