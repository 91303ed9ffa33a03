"""``rvmsim calibrate`` with a ChArUco board: corners found by their markers, partial views
used, the rendered camera recovered; the ChArUco ``--board`` spec and its errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rvmsim.calibrate import calibrate_fisheye, find_board_view, load_grey, parse_board_spec
from rvmsim.errors import RvmsimError

from .test_cli import _rvmsim
from .test_intrinsics import check_recovered

SPEC = "charuco:7x10:0.08:0.06"


def test_charuco_views_recover_the_rendered_camera(charuco_views):
    """fx, fy, cx, cy within 0.3 % and the lens radius within 0.5 px up to 80°, from the
    twelve views, the ones whose board reaches past the field included."""
    board = parse_board_spec(SPEC)
    views = [find_board_view(load_grey(p), board, p.name) for p in charuco_views]
    found = [v for v in views if v is not None]
    assert len(found) >= 10
    whole = (board.inner[0] * board.inner[1])
    assert any(len(v.corners) < whole for v in found)  # partial views are used
    calib = calibrate_fisheye(found, board, (640, 480))
    check_recovered(calib.K, calib.D)
    assert sum(v.used for v in calib.views) >= 10 and calib.rms_px < 0.5


def test_the_command_takes_a_charuco_board(charuco_views, tmp_path):
    res = _rvmsim("calibrate", charuco_views[0].parent, "--board", SPEC, "--out", "cal",
                  cwd=tmp_path)
    assert res.code == 0, res.stderr
    doc = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert doc["board"]["pattern"] == "charuco" and doc["board"]["squares"] == [7, 10]
    check_recovered(np.array(doc["K"]), np.array(doc["D"]))


@pytest.mark.parametrize("spec, match", [
    ("charuco:7x10:0.08:0.09", "below square_size"),
    ("charuco:7x10:0.08:0.06:DICT_NOPE", "not a cv2.aruco dictionary"),
    ("charuco:12x12:0.05:0.03", "has 50 markers"),
    ("charuco:7x10:0.08", "expected"),
])
def test_bad_charuco_specs_are_one_line_errors(spec, match, tmp_path):
    with pytest.raises(RvmsimError, match=match):
        parse_board_spec(spec)
    res = _rvmsim("calibrate", tmp_path, "--board", spec, "--out", "cal", cwd=tmp_path)
    assert res.code == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert "--board" in res.stderr and "Traceback" not in res.stderr
