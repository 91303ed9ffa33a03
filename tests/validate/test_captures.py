"""rvmsim.validate.captures: capture files, their output folders, and several captures
validated one after another: every capture read before any work (one that cannot be read is
raised), every error of a validation one capture's outcome (not raised)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.pose import capture_files, capture_folders
from rvmsim.validate import CaptureOutcome, Validation, validate_captures

from rvmsim.testing.captures import make_scene, scene_dict


def test_capture_files_expand_folders_by_name_and_keep_files(tmp_path: Path):
    folder = tmp_path / "caps"
    folder.mkdir()
    for name in ("b.PNG", "a.jpg", "notes.txt", "c.tiff"):
        (folder / name).write_bytes(b"")
    (folder / "sub.png").mkdir()  # a folder named like an image is not a capture
    single = tmp_path / "x.png"
    assert capture_files((folder, single)) == [folder / "a.jpg", folder / "b.PNG",
                                               folder / "c.tiff", single]
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(RvmsimError, match=r"empty: no captures .* \(--capture\)"):
        capture_files((empty,))


def test_capture_folders_number_a_name_met_again(tmp_path: Path):
    caps = [Path("a/front.png"), Path("b/front.png"), Path("rear.jpg"), Path("c/front.tif")]
    assert capture_folders(caps, tmp_path) == [tmp_path / "front", tmp_path / "front_2",
                                               tmp_path / "rear", tmp_path / "front_3"]


def test_an_unreadable_capture_is_refused_before_any_work(tmp_path: Path):
    """A good capture, then a missing and a blank one (issue #30): refused at once, naming
    the first bad one; no capture is validated, none reported, nothing written."""
    scene = make_scene(scene_dict())
    good = tmp_path / "good.png"
    noise = np.random.default_rng(1).integers(0, 255, (480, 640), dtype=np.uint8)
    cv2.imwrite(str(good), noise)
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.zeros((480, 640), np.uint8))
    missing = tmp_path / "missing.png"
    seen: list[CaptureOutcome] = []

    def never(result: Validation, folder: Path) -> list[Path]:
        raise AssertionError("no validation may run")

    for caps, bad, why in (([good, missing, blank], missing, "capture not found"),
                           ([good, blank], blank, "blank")):
        with pytest.raises(RvmsimError, match=why) as info:
            validate_captures(scene, caps, capture_folders(caps, tmp_path / "v"), never,
                              on_outcome=seen.append)
        assert str(bad) in str(info.value) and "\n" not in str(info.value)
    assert seen == [] and not (tmp_path / "v").exists()


def test_an_error_of_no_step_is_its_row(tmp_path: Path):
    """An error of no step (one capture's files not written) has no pictures to point at;
    the row carries the message."""
    out = CaptureOutcome("c.png", tmp_path / "v" / "c", None, "v/c: Permission denied",
                         "error")
    assert out.verdict == "ERROR" and out.message == out.error
    assert out.row()["error"] == out.error and out.row()["out_dir"] == str(tmp_path / "v" / "c")


def test_a_failed_step_points_at_its_pictures(tmp_path: Path):
    failed = CaptureOutcome("n.png", tmp_path / "n", None, "n.png: too few (step failed: "
                            "detection)", "detection")
    assert failed.message == f"{failed.error}; pictures in {tmp_path / 'n'}"


def test_every_capture_needs_its_folder():
    with pytest.raises(ValueError):
        validate_captures(make_scene(scene_dict()), [Path("a.png")], [], lambda r, f: [])
