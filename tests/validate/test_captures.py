"""rvmsim.validate.captures: capture files, their output folders, and several captures
validated one after another, every error one capture's outcome (not raised)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from rvmsim.errors import RvmsimError
from rvmsim.validate import (CaptureOutcome, Validation, capture_files, capture_folders,
                             validate_captures)

from .captures import make_scene, scene_dict


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


def test_unreadable_captures_are_outcomes_and_the_rest_still_run(tmp_path: Path):
    """A missing and a blank capture: two ERROR outcomes, each reported as it is known, in
    order; nothing raised and nothing written for them."""
    scene = make_scene(scene_dict())
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.zeros((480, 640), np.uint8))
    missing = tmp_path / "missing.png"
    caps = [missing, blank]
    seen: list[CaptureOutcome] = []

    def never(result: Validation, folder: Path) -> list[Path]:
        raise AssertionError("no validation finished")

    outcomes = validate_captures(scene, caps, capture_folders(caps, tmp_path / "v"), never,
                                 on_outcome=seen.append)
    assert seen == outcomes and [o.capture for o in outcomes] == [str(missing), str(blank)]
    assert [o.verdict for o in outcomes] == ["ERROR", "ERROR"]
    assert all(o.step == "error" and o.result is None for o in outcomes)
    assert "capture not found" in outcomes[0].error and "blank" in outcomes[1].error
    # An error of no step has no pictures to point at; the row carries the message.
    assert outcomes[1].message == outcomes[1].error and str(blank) in outcomes[1].message
    assert outcomes[1].row()["error"] == outcomes[1].error
    assert outcomes[1].row()["out_dir"] == str(tmp_path / "v" / "blank")
    assert not (tmp_path / "v").exists()


def test_a_failed_step_points_at_its_pictures(tmp_path: Path):
    failed = CaptureOutcome("n.png", tmp_path / "n", None, "n.png: too few (step failed: "
                            "detection)", "detection")
    assert failed.message == f"{failed.error}; pictures in {tmp_path / 'n'}"


def test_every_capture_needs_its_folder():
    with pytest.raises(ValueError):
        validate_captures(make_scene(scene_dict()), [Path("a.png")], [], lambda r, f: [])
