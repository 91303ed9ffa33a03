"""Imports of existing calibrations round-trip: camera block, OpenCV FileStorage, Kalibr
camchain, and an OCamCalib model fitted to Kannala-Brandt (fit error reported)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from rvmsim.calibrate import CalibrationInputError, camera_block, import_calibration
from rvmsim.scene import scene_from_dict

K = np.array([[304.3, 0.0, 481.3], [0.0, 324.8, 316.5], [0.0, 0.0, 1.0]])
D = np.array([-0.0416, 0.00315, -0.0024, 0.0000238])
SIZE = (960, 640)
BAIC_YAML = Path("/work/shared/reference/real-captures/baic-eu5-rear/back.yaml")


def _same(cam, k=K, d=D, atol_k=1e-9, atol_d=1e-12):
    np.testing.assert_allclose(cam.K, k, atol=atol_k)
    np.testing.assert_allclose(np.ravel(cam.D), d, atol=atol_d)


def test_camera_block_round_trips_and_loads_as_a_scene_camera(tmp_path):
    block = camera_block(K, D, SIZE, fov_deg=200)
    f = tmp_path / "camera.yaml"
    f.write_text(yaml.safe_dump({"camera": block}))
    cam = import_calibration(f)
    _same(cam)
    assert cam.image_size == SIZE and cam.source_format == "scene"
    scene = scene_from_dict({"name": "t", "camera": {**block, "mount": {"position": [0, -1, 0]}},
                             "test_site": {"fmvss": False}})
    np.testing.assert_allclose(scene.fisheye_camera().K, K)
    np.testing.assert_allclose(np.ravel(scene.fisheye_camera().D), D)


def test_opencv_filestorage_round_trips(tmp_path):
    f = tmp_path / "cam.yaml"
    fs = cv2.FileStorage(str(f), cv2.FILE_STORAGE_WRITE)
    fs.write("camera_matrix", K)
    fs.write("dist_coeffs", D.reshape(4, 1))
    fs.write("resolution", np.array(SIZE, dtype=np.int32).reshape(2, 1))
    fs.release()
    cam = import_calibration(f)
    _same(cam)
    assert cam.image_size == SIZE and cam.source_format == "opencv"


@pytest.mark.skipif(not BAIC_YAML.is_file(), reason="BAIC reference calibration not found")
def test_the_baic_back_yaml_imports():
    cam = import_calibration(BAIC_YAML)
    assert cam.image_size == (960, 640)
    assert cam.K[0, 0] == pytest.approx(304.349, abs=1e-3)
    assert cam.K[1, 1] == pytest.approx(324.777, abs=1e-3)
    assert cam.D[0] == pytest.approx(-0.041568, abs=1e-6)


def test_kalibr_camchain_round_trips(tmp_path):
    f = tmp_path / "camchain.yaml"
    f.write_text(yaml.safe_dump({"cam0": {
        "camera_model": "pinhole", "distortion_model": "equidistant",
        "intrinsics": [float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2])],
        "distortion_coeffs": D.tolist(), "resolution": list(SIZE), "rostopic": "/cam0"}}))
    cam = import_calibration(f)
    _same(cam)
    assert cam.source_format == "kalibr"


def test_kalibr_other_models_are_refused(tmp_path):
    f = tmp_path / "camchain.yaml"
    f.write_text(yaml.safe_dump({"cam0": {"camera_model": "omni", "distortion_model": "radtan",
                                          "intrinsics": [1, 2, 3, 4, 5]}}))
    with pytest.raises(CalibrationInputError, match="pinhole-equidistant"):
        import_calibration(f)


def _ocam_file(path: Path, k: np.ndarray, d: np.ndarray, size: tuple[int, int]) -> None:
    """An OCamCalib calib_results.txt for the Kannala-Brandt camera (k, d): its polynomial
    z(ρ) fitted to the camera's θ(ρ) (ρ in px from the centre; square pixels)."""
    f = k[0, 0]
    th = np.linspace(0, np.radians(98), 400)
    rho = f * th * (1 + d[0] * th**2 + d[1] * th**4 + d[2] * th**6 + d[3] * th**8)
    z = -rho / np.tan(np.maximum(th, 1e-9))
    z[0] = -f
    # z = a0 + a2 ρ² + … + a8 ρ⁸ (OCamCalib has no linear term), fitted in ρ / f
    powers = [0, 2, 3, 4, 5, 6, 7, 8]
    A = np.stack([(rho / f) ** p for p in powers], axis=1)
    coef = np.linalg.lstsq(A, z, rcond=None)[0]
    poly = [0.0] * 9
    for p, c in zip(powers, coef):
        poly[p] = c / f**p
    text = ("#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in "
            "MATLAB). These are used by cam2world\n\n"
            f"{len(poly)} " + " ".join(f"{c:.12e}" for c in poly) + "\n\n"
            "#polynomial coefficients for the inverse mapping function (ocam_model.invpol in "
            "MATLAB). These are used by world2cam\n\n3 1.0 2.0 3.0\n\n"
            '#center: "row" and "column" coordinates (x, y) of the center of distortion in '
            "the image\n\n"
            f"{k[1, 2]:.6f} {k[0, 2]:.6f}\n\n"
            '#affine parameters "c", "d", "e"\n\n1.000000 0.000000 0.000000\n\n'
            '#image size: "height" and "width"\n\n'
            f"{size[1]} {size[0]}\n")
    path.write_text(text)


def test_ocamcalib_is_fitted_to_kannala_brandt_with_its_error(tmp_path):
    k = np.array([[300.0, 0, 481.0], [0, 300.0, 316.0], [0, 0, 1.0]])
    f = tmp_path / "calib_results.txt"
    _ocam_file(f, k, D, SIZE)
    cam = import_calibration(f)
    assert cam.source_format == "ocamcalib" and cam.image_size == SIZE
    assert 0 < cam.fit_rms_px < 0.5 and cam.fit_max_px < 1.5
    np.testing.assert_allclose(cam.K[:2, 2], k[:2, 2], atol=0.2)
    th = np.radians(np.linspace(0, 80, 81))

    def radius(f0, d):
        return f0 * th * (1 + d[0] * th**2 + d[1] * th**4 + d[2] * th**6 + d[3] * th**8)

    assert np.abs(radius(cam.K[0, 0], cam.D) - radius(300.0, D)).max() < 1.0


@pytest.mark.parametrize("text, match", [
    ("just: [1, 2]\n", "not a known calibration format"),
    ("cam0: [unclosed\n", "malformed YAML"),
    ("#polynomial coefficients\n\n5 1 2\n", "OCamCalib"),
])
def test_bad_calibration_files_are_one_line_errors(tmp_path, text, match):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(CalibrationInputError, match=match) as info:
        import_calibration(f)
    assert "\n" not in str(info.value) and str(f) in str(info.value)
