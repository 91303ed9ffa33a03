"""Names that are not valid UTF-8 (issue #45): a Latin-1 file or folder name, or a
reviewer's name given in Latin-1 bytes, reaches Python as a str with surrogate escapes
(``'car\\udcff.png'`` for the bytes ``b'car\\xff.png'``).  Each command exits with its
normal status, writes valid UTF-8 files (the name shown as ``\\xff`` in HTML), and its JSON
reads back to the very same name.

Such names are made through bytes paths (:func:`os.fsencode`); a file system that refuses
them (macOS APFS, some network shares) skips the tests.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from ..cli_runner import Outcome, run_in_process

#: A Latin-1 byte that is not UTF-8, as Python's file-system decoding gives it.
BAD = os.fsdecode(b"\xff")
#: A reviewer's name in Latin-1 bytes on the command line.
REVIEWER = os.fsdecode("José Müller".encode("latin-1"))


def _bad_name_allowed(folder: Path) -> bool:
    probe = os.fsencode(folder) + b"/probe\xff"
    try:
        os.mkdir(probe)
    except OSError:
        return False
    os.rmdir(probe)
    return True


@pytest.fixture
def latin1(case_dir: Path) -> Path:
    """The case folder (a finished run, its scene), where names may be non-UTF-8 bytes."""
    if os.fsencode("x" + BAD) != b"x\xff" or not _bad_name_allowed(case_dir):
        pytest.skip("this file system (or encoding) does not take a name that is not UTF-8")
    return case_dir


def assert_normal(out: Outcome, codes: tuple[int, ...] = (0, 1)) -> None:
    """The command's normal exit status, no traceback."""
    assert "Traceback" not in out.stderr, out.stderr[-3000:]
    assert out.code in codes, out.stderr


def assert_utf8_files(folder: Path) -> None:
    """Every text file in ``folder`` is valid UTF-8."""
    for p in folder.rglob("*"):
        if p.suffix in (".html", ".json", ".yaml", ".csv"):
            p.read_bytes().decode("utf-8")  # raises on a surrogate written as bytes


def test_signoff_reviewer_in_latin1(latin1: Path):
    out = run_in_process(["signoff", "run", "--out", "so", "--reviewer", REVIEWER, "--no-pdf",
                          "--no-progress"], cwd=latin1)
    assert_normal(out)
    assert_utf8_files(latin1 / "so")
    assert json.loads((latin1 / "so" / "signoff.json").read_text())["reviewer"] == REVIEWER
    assert "Jos\\xe9 M\\xfcller" in (latin1 / "so" / "signoff.html").read_text()


def test_signoff_and_report_of_a_run_folder_named_in_latin1(latin1: Path):
    run = latin1 / f"run{BAD}"
    shutil.move(latin1 / "run", run)
    out = run_in_process(["signoff", run.name, "--out", f"so{BAD}", "--no-pdf",
                          "--no-progress"], cwd=latin1)
    assert_normal(out)
    so = latin1 / f"so{BAD}"
    assert_utf8_files(so)
    doc = json.loads((so / "signoff.json").read_text())
    assert doc["run"] == str(run.resolve())
    assert Path(doc["params_file"]).is_file()  # the path, as written, names the file
    rep = run_in_process(["report", run.name, "--no-progress"], cwd=latin1)
    assert_normal(rep, (0,))
    assert "run\\xff" in (run / "report.html").read_text(encoding="utf-8")


def test_robustness_of_a_scene_named_in_latin1(latin1: Path):
    scene = latin1 / f"sc{BAD}.yaml"
    shutil.copy(latin1 / "scene.yaml", scene)
    out = run_in_process(["robustness", scene.name, "--params", "run/top/rank_1.yaml",
                          "--samples", "4", "--scales", "1", "--workers", "1", "--out", "rob",
                          "--no-progress"], cwd=latin1)
    assert_normal(out)
    assert_utf8_files(latin1 / "rob")
    doc = json.loads((latin1 / "rob" / "robustness.json").read_text())
    scenes = [f["path"] for f in doc["inputs"]["files"] if f["role"] == "scene"]
    assert scenes == [str(scene.resolve())]


def test_eol_of_a_capture_named_in_latin1(tmp_path: Path):
    from rvmsim.compensation import Deviation
    from rvmsim.testing.stations import write_capture, write_inputs

    if not _bad_name_allowed(tmp_path):
        pytest.skip("this file system does not take a name that is not UTF-8")
    scene, params = write_inputs(tmp_path)
    cap = write_capture(tmp_path / "caps" / f"car{BAD}.png", Deviation(1, 0, 0, 0.2, 0, 0))
    out = run_in_process(["eol", scene, "--params", params, "--capture", cap, "--out",
                          tmp_path / "out", "--no-progress"],
                         env={"RVMSIM_CACHE": str(tmp_path / "cache")})
    assert_normal(out)
    assert_utf8_files(tmp_path / "out")
    doc = json.loads((tmp_path / "out" / "eol.json").read_text())
    assert [c["capture"] for c in doc["results"]] == [str(cap)]
