"""``rvmsim calibrate --import`` (issue #30): every imported camera is checked before
anything is written (focal lengths, principal point, image size, distortion, each named by
its format's key), Kalibr YAML is read within the YAML limits, a truncated FileStorage is
one line, an OCamCalib model of an absurd size is refused before the fit, and one whose
Kannala-Brandt fit is over :data:`rvmsim.calibrate.imports.MAX_FIT_RMS_PX` is refused
unless ``--accept-fit-error``.  A good file of each format still imports."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from ..cli_runner import run_in_process
from .harness import Case, check_case

CAL = ("calibrate", "--out", "o", "--import")
GOOD_K = ([100.0, 0.0, 160.0], [0.0, 100.0, 120.0], [0.0, 0.0, 1.0])


def _kalibr(intrinsics="100, 100, 160, 120", coeffs="0, 0, 0, 0", resolution="320, 240"):
    return ("cam0:\n  camera_model: pinhole\n  distortion_model: equidistant\n"
            f"  intrinsics: [{intrinsics}]\n  distortion_coeffs: [{coeffs}]\n"
            f"  resolution: [{resolution}]\n")


def _opencv(k=GOOD_K, resolution: tuple[int, int] | None = (320, 240)) -> str:
    def mat(rows, cols, dt, data):
        return (f"!!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: {dt}\n"
                f"   data: [ {', '.join(str(x) for x in data)} ]\n")
    text = ("%YAML:1.0\n---\ncamera_matrix: " + mat(3, 3, "d", [x for r in k for x in r])
            + "dist_coeffs: " + mat(4, 1, "d", [0.0] * 4))
    if resolution is not None:
        text += "resolution: " + mat(2, 1, "i", resolution)
    return text


def _ocam(poly="3 -100 0 0.01", centre="120 160", size="240 320") -> str:
    return (f"#polynomial coefficients for the DIRECT mapping function\n\n{poly}\n\n"
            "#polynomial coefficients for the inverse mapping function\n\n3 1 2 3\n\n"
            f"#center: row and column\n\n{centre}\n\n#affine parameters c d e\n\n1 0 0\n\n"
            f"#image size: height and width\n\n{size}\n")


def _write(name: str, text: str):
    return lambda folder: (folder / name).write_text(text)


K, O, T = "camchain.yaml", "cam.yaml", "calib_results.txt"
#: (case id, file, text, names in the line)
FILES = [
    ("kalibr-negative-focal", K, _kalibr("-100, 100, 160, 120"), ("cam0.intrinsics", "fx")),
    ("kalibr-zero-focal", K, _kalibr("100, 0, 160, 120"), ("cam0.intrinsics", "fy")),
    ("kalibr-huge-focal", K, _kalibr("1e9, 100, 160, 120"), ("cam0.intrinsics", "fx")),
    ("kalibr-size-0x0", K, _kalibr(resolution="0, 0"), ("cam0.resolution",)),
    ("kalibr-size-1e9", K, _kalibr(resolution="1000000000, 1000000000"),
     ("cam0.resolution",)),
    ("kalibr-size-fraction", K, _kalibr(resolution="320.5, 240"), ("cam0.resolution",)),
    ("kalibr-centre-nan", K, _kalibr("100, 100, .nan, 120"), ("cam0.intrinsics",)),
    ("kalibr-centre-far", K, _kalibr("100, 100, 16000, 120"), ("cam0.intrinsics", "cx")),
    ("kalibr-distortion-inf", K, _kalibr(coeffs="0, .inf, 0, 0"),
     ("cam0.distortion_coeffs",)),
    ("kalibr-distortion-1e300", K, _kalibr(coeffs="1e300, 0, 0, 0"),
     ("cam0.distortion_coeffs",)),
    ("kalibr-deeply-nested", K, "cam0: " + "[" * 5000 + "]" * 5000 + "\n", ("limits",)),
    ("kalibr-alias-bomb", K, "a: &a [x, x, x, x, x, x, x, x, x, x]\n"
     + "".join(f"{c}: &{c} [{', '.join(['*' + p] * 10)}]\n"
               for p, c in zip("abcdef", "bcdefg")), ("limits",)),
    ("opencv-zero-focal", O, _opencv(([0.0, 0, 160], [0, 100, 120], [0, 0, 1])),
     ("camera_matrix", "focal length fx")),
    ("opencv-zero-focal-no-size", O, _opencv(([0.0, 0, 160], [0, 100, 120], [0, 0, 1]), None),
     ("camera_matrix", "focal length fx")),
    ("opencv-not-a-camera-matrix", O, _opencv(([100.0, 0, 160], [0, 100, 120], [1, 1, 1])),
     ("camera_matrix",)),
    ("opencv-size-negative", O, _opencv(resolution=(-320, 240)), ("resolution",)),
    ("opencv-no-size", O, _opencv(resolution=None), ("resolution", "no image size")),
    ("ocam-size-99999", T, _ocam(size="99999 99999"), ("image size",)),
    ("ocam-size-zero", T, _ocam(size="0 320"), ("image size",)),
    ("ocam-flat-polynomial", T, _ocam("3 -20 0 0"), ("polynomial", "px RMS",
                                                     "--accept-fit-error")),
    ("ocam-wild-polynomial", T, _ocam("4 -100 0 0.02 -1e-4"), ("polynomial", "px RMS")),
    ("ocam-no-rays", T, _ocam("3 0 0 0"), ("polynomial",)),
    ("ocam-centre-far", T, _ocam(centre="12000 16000"), ("centre",)),
]
CASES = [Case(f"import-{i}", CAL + (name,), (name, *names), _write(name, text))
         for i, name, text, names in FILES]
TRUNCATED_AT = (40, 100, 150, 200, 230)
CASES += [Case(f"import-opencv-truncated-{n}", CAL + (O,), (O,),
               _write(O, _opencv()[:n])) for n in TRUNCATED_AT]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_import(case, tmp_path):
    out = check_case(case, tmp_path)
    assert not (tmp_path / "o").exists(), out.stderr  # nothing written


def test_a_bad_fit_is_written_with_a_warning_when_accepted(tmp_path):
    """``--accept-fit-error``: the flat polynomial's camera is written, its fit error a
    warning on stderr (one line) naming the file."""
    (tmp_path / T).write_text(_ocam("3 -20 0 0"))
    out = run_in_process(["calibrate", "--out", "o", "--import", T, "--accept-fit-error"],
                         cwd=tmp_path)
    assert out.code == 0, out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rvmsim: warning: ") and T in lines[0]
    assert "px RMS" in lines[0]
    cam = yaml.safe_load((tmp_path / "o" / "camera.yaml").read_text())["camera"]
    assert cam["image_size"] == [320, 240]


@pytest.mark.parametrize("name, text, fmt", [
    (K, _kalibr(), "kalibr"), (O, _opencv(), "opencv"), (T, _ocam(), "ocamcalib"),
    (O, _opencv(resolution=None).replace("---\n", "---\nimage_width: 320\nimage_height: 240\n"),
     "opencv"),
])
def test_a_good_file_of_each_format_imports(tmp_path, name, text, fmt):
    (tmp_path / name).write_text(text)
    out = run_in_process(["calibrate", "--out", "o", "--import", name], cwd=tmp_path)
    assert out.code == 0 and out.stderr == "", out.stderr
    assert f"({fmt})" in out.stdout
    cam = yaml.safe_load((tmp_path / "o" / "camera.yaml").read_text())["camera"]
    assert cam["image_size"] == [320, 240]
    K_out = np.array(cam["intrinsics"]["K"])
    if fmt == "ocamcalib":  # fitted: the centre where the file puts it, to a fraction of a px
        np.testing.assert_allclose(K_out[:2, 2], [160, 120], atol=0.2)
    else:
        np.testing.assert_allclose(K_out, GOOD_K)


def test_the_help_states_the_fit_limit():
    """``calibrate --help`` gives the limit ``--accept-fit-error`` lifts, as the code has it."""
    from rvmsim.calibrate.imports import MAX_FIT_RMS_PX

    out = run_in_process(["calibrate", "--help"])
    assert out.code == 0
    assert f"worse than {MAX_FIT_RMS_PX:g} px RMS" in " ".join(out.stdout.split())
