"""Existing calibrations read into a Kannala-Brandt camera: OpenCV FileStorage YAML
(``camera_matrix``, ``dist_coeffs``), a Kalibr camchain (pinhole-equidistant), an
OCamCalib / Scaramuzza ``calib_results.txt`` (fitted to Kannala-Brandt, with the fit error
in px), or a scene's camera block (as :func:`rvmsim.calibrate.camera_block` writes it).

Every camera read is checked before it is returned (:func:`_checked`), with the limits a
scene's camera is held to: an image size of 16..16,384 px a side within the pixel limit
(:func:`rvmsim._io.image_size_problem`), positive focal lengths within
:data:`rvmsim.scene.FOCAL_FACTORS` of the longest side, a finite principal point at most an
image size outside the image, finite distortion coefficients of at most
:data:`MAX_DISTORTION` in magnitude.  Each problem is one line naming the file and the key
of its own format (``camera_matrix``, ``cam0.intrinsics``, ``resolution`` …).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from scipy.optimize import least_squares

from .._io import image_size_problem, parse_yaml, read_text
from ..scene import FOCAL_FACTORS
from .board import CalibrationInputError

__all__ = ["ImportedCamera", "import_calibration", "fit_kannala_brandt", "fit_error_text",
           "MAX_FIT_RMS_PX",
           "MAX_DISTORTION", "MIN_IMAGE_SIDE_PX"]

#: Largest RMS error (px) of an OCamCalib model's Kannala-Brandt fit that ``calibrate
#: --import`` writes without ``--accept-fit-error``: a model that four Kannala-Brandt terms
#: describe fits to about 0.1 px; a flat or degenerate polynomial fits to tens of px.
MAX_FIT_RMS_PX = 1.0
#: Largest magnitude of a Kannala-Brandt distortion coefficient k1..k4 imported (real
#: lenses have |k| well below 1).
MAX_DISTORTION = 1000.0
#: Shortest image side of an imported camera, px (a scene's camera needs as much).
MIN_IMAGE_SIDE_PX = 16
#: Fewest pixels of an OCamCalib model's 41 × 31 grid whose rays must lie within 100° of
#: the axis for the fit (it has 8 unknowns).
MIN_FIT_PIXELS = 16


@dataclass(frozen=True)
class _Keys:
    """The keys of a format that hold the focal lengths, the principal point, the
    distortion coefficients and the image size (for messages)."""

    focal: str
    centre: str
    distortion: str
    size: str


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
    if a.size != n:
        raise _err(path, key, f"expected {n} finite numbers, got {a.size}")
    if not np.all(np.isfinite(a)):
        raise _err(path, key, f"expected {n} finite numbers, got "
                   f"{', '.join(f'{x:g}' for x in a)}")
    return a


def _cv2_message(err: BaseException) -> str:
    """The last line of a cv2.error (its "error: (-215:…) …" part)."""
    text = str(err).strip().splitlines()[-1] if str(err).strip() else type(err).__name__
    return text.split(" error: ")[-1][:160]


def _size(path: Path, key: str, value: object) -> tuple[int, int]:
    """(width, height) px of a size of two whole numbers (their limits: :func:`_checked`)."""
    w, h = _floats(path, key, value, 2)
    if w != round(w) or h != round(h):
        raise _err(path, key, f"the image size must be whole pixels, got {w:g}x{h:g}")
    return int(w), int(h)


def _opencv(path: Path) -> ImportedCamera:
    """OpenCV FileStorage: ``camera_matrix``, ``dist_coeffs`` and ``resolution`` (or
    ``image_width`` and ``image_height``, as OpenCV's calibration sample writes them)."""

    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except (cv2.error, SystemError) as err:  # a parse error comes as a SystemError from it
        cause = err.__cause__ or err.__context__ or err
        raise _err(path, "", "not a readable OpenCV FileStorage file (truncated or corrupt?): "
                   f"{_cv2_message(cause)}") from None
    mats: dict[str, Any] = {}
    key, size_key = "", "resolution"
    try:
        for key in ("camera_matrix", "dist_coeffs", "resolution"):
            node = fs.getNode(key)
            mats[key] = None if node.empty() else node.mat()
            if not node.empty() and mats[key] is None:
                raise _err(path, key, "expected an !!opencv-matrix (rows, cols, dt, data)")
        if mats["resolution"] is None:
            nodes = [fs.getNode(k) for k in ("image_width", "image_height")]
            if not any(n.empty() for n in nodes):
                key = size_key = "image_width"
                mats["resolution"] = [n.real() for n in nodes]
    except (cv2.error, SystemError) as err:
        cause = err.__cause__ or err.__context__ or err
        raise _err(path, key, f"unreadable: {_cv2_message(cause)}") from None
    finally:
        fs.release()
    K, D, res = mats["camera_matrix"], mats["dist_coeffs"], mats["resolution"]
    if K is None:
        raise _err(path, "camera_matrix", "missing (OpenCV FileStorage)")
    if D is None:
        raise _err(path, "dist_coeffs", "missing (OpenCV FileStorage)")
    k = _floats(path, "camera_matrix", K, 9).reshape(3, 3)
    d = _floats(path, "dist_coeffs", D, 4)
    size = None if res is None else _size(path, size_key, res)
    return _checked(path, ImportedCamera(k, d, size, "opencv"),
                    _Keys("camera_matrix", "camera_matrix", "dist_coeffs", size_key))


def _kalibr(path: Path, doc: dict[Any, Any]) -> ImportedCamera:
    name = sorted((k for k in doc if str(k).startswith("cam")), key=str)[0]
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
    size = None if res is None else _size(path, f"{name}.resolution", res)
    K = np.array([[fu, 0, pu], [0, fv, pv], [0, 0, 1.0]])
    return _checked(path, ImportedCamera(K, d, size, "kalibr"),
                    _Keys(f"{name}.intrinsics", f"{name}.intrinsics",
                          f"{name}.distortion_coeffs", f"{name}.resolution"))


def _camera_block(path: Path, doc: dict[Any, Any]) -> ImportedCamera:
    cam = doc.get("camera", doc)
    try:
        K = cam["intrinsics"]["K"]
        k = cam["lens"]["k"]
        res = cam["image_size"]
    except (KeyError, TypeError):
        raise _err(path, "camera", "expected image_size, intrinsics.K and lens.k") from None
    return _checked(path, ImportedCamera(
        _floats(path, "camera.intrinsics.K", K, 9).reshape(3, 3),
        _floats(path, "camera.lens.k", k, 4), _size(path, "camera.image_size", res), "scene"),
        _Keys("camera.intrinsics.K", "camera.intrinsics.K", "camera.lens.k",
              "camera.image_size"))


def _checked(path: Path, cam: ImportedCamera, keys: _Keys) -> ImportedCamera:
    """``cam`` when a scene could use it (see the module docstring), else one line naming
    ``path`` and the key at fault.  Without an image size only what needs none is checked
    (:func:`rvmsim.calibrate.import_camera` refuses the camera for lack of it)."""
    K, d = cam.K, np.ravel(cam.D)
    fx, fy, cx, cy = (float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]))
    for name, f in (("fx", fx), ("fy", fy)):
        if not (math.isfinite(f) and f > 0):
            raise _err(path, keys.focal, f"the focal length {name} = {f:g} px must be positive")
    if not (math.isfinite(cx) and math.isfinite(cy)):
        raise _err(path, keys.centre, f"the principal point ({cx:g}, {cy:g}) px must be finite")
    if K[1, 0] != 0 or K[2, 0] != 0 or K[2, 1] != 0 or K[2, 2] != 1 or abs(K[0, 1] / fx) >= 1:
        raise _err(path, keys.focal, "not a camera matrix [[fx, s, cx], [0, fy, cy], "
                                     "[0, 0, 1]] with |s| < fx")
    if np.any(np.abs(d) > MAX_DISTORTION):
        raise _err(path, keys.distortion, "distortion coefficients must be at most "
                   f"{MAX_DISTORTION:g} in magnitude, got {', '.join(f'{x:g}' for x in d)}")
    if cam.image_size is None:
        return cam
    w, h = cam.image_size
    problem = image_size_problem(w, h, min_side=MIN_IMAGE_SIDE_PX)
    if problem is not None:
        raise _err(path, keys.size, problem)
    lo, hi = FOCAL_FACTORS[0] * max(w, h), FOCAL_FACTORS[1] * max(w, h)
    for name, f in (("fx", fx), ("fy", fy)):
        if not lo <= f <= hi:
            raise _err(path, keys.focal, f"the focal length {name} = {f:g} px is outside "
                       f"[{lo:g}, {hi:g}] ({FOCAL_FACTORS[0]:g} to {FOCAL_FACTORS[1]:g} times "
                       f"the longest image side of {w}x{h} px)")
    for name, c, n in (("cx", cx, w), ("cy", cy, h)):
        if not -n <= c <= 2 * n:
            raise _err(path, keys.centre, f"the principal point {name} = {c:g} px is outside "
                       f"[{-n}, {2 * n}] (at most an image size outside the {w}x{h} px image)")
    return cam


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
    if not all(math.isfinite(x) for r in rows for x in r):
        raise _err(path, "", "OCamCalib: every number must be finite")
    if (len(rows) < 5 or len(rows[0]) < 2 or rows[0][0] != len(rows[0]) - 1
            or len(rows[2]) < 2 or len(rows[3]) < 3 or len(rows[4]) < 2):
        raise _err(path, "", "expected the OCamCalib calib_results.txt layout (polynomial, "
                             "inverse polynomial, centre, affine c d e, height width)")
    h, w = rows[4][:2]
    if h != round(h) or w != round(w):
        raise _err(path, OCAM_SIZE, f"the image size must be whole pixels, got {h:g} {w:g}")
    problem = image_size_problem(int(w), int(h), min_side=MIN_IMAGE_SIDE_PX)
    if problem is not None:
        raise _err(path, OCAM_SIZE, problem)
    c, d, e = rows[3][:3]
    if abs(c - d * e) < 1e-12:
        raise _err(path, "affine parameters c d e", "OCamCalib: the affine matrix [c d; e 1] "
                                                    "must be invertible")
    return rows


#: What the messages call the OCamCalib file's size line ("#image size: height and width").
OCAM_SIZE = "image size (height width)"


def _ocam(path: Path, text: str) -> ImportedCamera:
    rows = _ocam_numbers(path, text)
    poly = np.array(rows[0][1:])
    xc, yc = rows[2][:2]  # row, column of the distortion centre
    c, d, e = rows[3][:3]
    h, w = int(rows[4][0]), int(rows[4][1])
    # Rays of a grid of pixels (cam2world), then Kannala-Brandt fitted to them.
    grid_c, grid_r = np.meshgrid(np.linspace(0, w - 1, 41), np.linspace(0, h - 1, 31))
    col, row = grid_c.ravel(), grid_r.ravel()
    with np.errstate(all="ignore"):  # a wild polynomial overflows: its rays are dropped
        inv = 1.0 / (c - d * e)
        xp = inv * ((row - xc) - d * (col - yc))
        yp = inv * (-e * (row - xc) + c * (col - yc))
        rho = np.hypot(xp, yp)
        z = np.polyval(poly[::-1], rho)
        theta = np.arctan2(rho, -z)
        keep = (theta < np.radians(100)) & (rho > 1e-9) & np.isfinite(theta)
        dirs = np.stack([yp / rho, xp / rho], axis=1)  # (column, row) unit direction
    if np.count_nonzero(keep) < MIN_FIT_PIXELS:
        raise _err(path, "polynomial", f"OCamCalib: the polynomial sends {np.count_nonzero(keep)} "
                   f"of the 41x31 grid's pixels to rays within 100° of the axis (a fit needs "
                   f"{MIN_FIT_PIXELS}): a degenerate model, or the centre outside the image")
    pix = np.stack([col, row], axis=1)
    try:
        K, D, rms, mx = fit_kannala_brandt(theta[keep], dirs[keep], pix[keep], (w, h))
    except (ValueError, np.linalg.LinAlgError) as err:
        raise _err(path, "polynomial", f"OCamCalib: no Kannala-Brandt fit ({err})") from None
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(D)) and math.isfinite(rms)):
        raise _err(path, "polynomial", "OCamCalib: the Kannala-Brandt fit diverged")
    cam = ImportedCamera(K, D, (w, h), "ocamcalib", rms, mx)
    try:
        return _checked(path, cam, _Keys("polynomial", "centre (row column)", "polynomial",
                                         OCAM_SIZE))
    except CalibrationInputError as err:
        if rms <= MAX_FIT_RMS_PX:
            raise
        raise _err(path, "polynomial", f"{fit_error_text(cam)}, and the camera fitted is "
                   f"unusable ({err.key}: {err.message})") from None


def fit_error_text(cam: ImportedCamera) -> str:
    """What the fit error of an OCamCalib model over :data:`MAX_FIT_RMS_PX` says."""
    return (f"the Kannala-Brandt fit of the OCamCalib model is {cam.fit_rms_px:.3g} px RMS "
            f"(max {cam.fit_max_px:.3g} px), over the limit of {MAX_FIT_RMS_PX:g} px RMS "
            "(a flat or degenerate polynomial, or a lens beyond four Kannala-Brandt terms)")


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
        One line naming the file (and the key) when it is unreadable (also a truncated
        FileStorage, YAML over the limits of :func:`rvmsim._io.parse_yaml`), of no known
        format, or its camera is unusable (module docstring; an OCamCalib model that no
        Kannala-Brandt camera can be fitted to).
    """
    p = Path(path)
    text = read_text(p, CalibrationInputError, what="calibration file")
    if text.lstrip().startswith("%YAML") or "camera_matrix" in text:
        return _opencv(p)
    if text.lstrip().startswith("#") and "polynomial" in text.lower():
        return _ocam(p, text)
    doc = parse_yaml(text, str(p), CalibrationInputError)
    if isinstance(doc, dict) and any(str(k).startswith("cam") and isinstance(v, dict)
                                     and "camera_model" in v for k, v in doc.items()):
        return _kalibr(p, doc)
    if isinstance(doc, dict) and ("camera" in doc or "intrinsics" in doc):
        return _camera_block(p, doc)
    raise _err(p, "", "not a known calibration format (OpenCV FileStorage YAML, Kalibr "
                      "camchain, OCamCalib calib_results.txt, scene camera block)")
