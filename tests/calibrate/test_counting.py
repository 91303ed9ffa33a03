"""The board's counting: ``squares:`` and ``inner:`` specs, and a board counted by its
squares (or one too few) found by the other counting, with a one-line hint, quickly."""

from __future__ import annotations

import shutil
import time

import pytest

from rvmsim.calibrate import parse_board_spec
from rvmsim.errors import RvmsimError

from ..cli_runner import run_in_process
from .conftest import SQUARE, SQUARES

INNER = f"{SQUARES[0] - 1}x{SQUARES[1] - 1}"


def test_specs_say_which_counting():
    assert parse_board_spec("squares:8x10:0.05").inner == (7, 9)
    assert parse_board_spec("inner:7x9:0.05").inner == (7, 9)
    assert parse_board_spec("7x9:0.05").inner == (7, 9)
    assert parse_board_spec("7x9:0.05").describe() == "7x9 inner corners (8x10 squares)"
    with pytest.raises(RvmsimError, match="squares must be 3..201"):
        parse_board_spec("squares:2x10:0.05")


@pytest.mark.parametrize("spec, gave", [
    (f"{SQUARES[0]}x{SQUARES[1]}:{SQUARE}", "which counts its squares"),
    pytest.param(f"squares:{INNER}:{SQUARE}", "which counts its inner corners",
                 marks=pytest.mark.slow),
    pytest.param(f"{SQUARES[0] - 2}x{SQUARES[1] - 2}:{SQUARE}", "one fewer each way",
                 marks=pytest.mark.slow),
])
def test_a_miscounted_board_gets_the_other_counting(board_views, tmp_path, spec, gave):
    caps = tmp_path / "caps"
    caps.mkdir()
    for p in board_views[:5]:
        shutil.copy(p, caps / p.name)
    t0 = time.monotonic()
    res = run_in_process(("calibrate", "caps", "--board", spec, "--out", "cal"), cwd=tmp_path)
    took = time.monotonic() - t0
    assert res.code == 2, res.stdout
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert "not found in the first 3 captures" in lines[0]
    assert f"looks like {INNER} inner corners" in lines[0] and gave in lines[0]
    assert f"pass --board {INNER}:{SQUARE}" in lines[0]
    # Three failed searches and the quick retry, not a search of every capture.
    assert took < 60, took
    assert not (tmp_path / "cal" / "calibration.json").exists()
