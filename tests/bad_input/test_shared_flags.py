"""Bad flags and scenes of shared tuning (`rvmsim tune SCENE1 SCENE2 … --shared`): one stderr
line naming the option or the scene file, exit status 2, no traceback, the runs given
byte-identical afterwards."""

from __future__ import annotations

import json
import shutil
import sqlite3
from pathlib import Path

import pytest

from .conftest import SMALL_SCENE, small_scene
from ..cli_runner import run_in_process
from .harness import Case, check_case

S = SMALL_SCENE
NEW = ("--out", "new", "--no-progress", "--workers", "1")


def _variant(name: str = "b.yaml", edit: dict | None = None):
    """A setup writing a second small scene ``name`` (``edit``: as small_scene's)."""
    def setup(folder: Path) -> None:
        sub = folder / "variant"
        sub.mkdir(exist_ok=True)
        small_scene(sub, edit or {"vehicle.bumper.top": 0.8})
        shutil.move(sub / SMALL_SCENE, folder / name)
        sub.rmdir()
    return setup


def _junk(name: str):
    def setup(folder: Path) -> None:
        (folder / name).write_text("camera: [\n")
    return setup


def _shared_run(folder: Path) -> None:
    """A finished shared run of scene.yaml and b.yaml in ``shared/``."""
    _variant()(folder)
    out = run_in_process(["tune", S, "b.yaml", "--shared", "--strategy", "random", "--budget",
                          "20", "--out", "shared", "--no-progress", "--workers", "1"],
                         cwd=folder)
    # 1: no setting of so short a search passes both scenes (the summary says which ECs)
    assert out.code in (0, 1) and (folder / "shared" / "best" / "members.json").is_file(), \
        out.stderr


def _changed_shared_run(folder: Path) -> None:
    """A finished shared run, then its b.yaml changed."""
    _shared_run(folder)
    _variant(edit={"vehicle.bumper.top": 0.82})(folder)


def _bad_aggregate_run(folder: Path) -> None:
    """A finished shared run whose stored aggregate is not one this version knows."""
    _shared_run(folder)
    db = sqlite3.connect(folder / "shared" / "run.sqlite")
    with db:
        db.execute("UPDATE meta SET value = ? WHERE key = 'aggregate'", (json.dumps("max"),))
    db.close()


CASES = [
    Case("shared-one-scene", ("tune", S, "--shared", *NEW), ("--shared", "two scenes")),
    Case("shared-two-scenes-without-flag", ("tune", S, "b.yaml", *NEW), ("--shared",),
         setup=_variant()),
    Case("shared-resume-with-scenes", ("tune", S, "b.yaml", "--resume", "run", "--no-progress"),
         ("--resume",), setup=_variant(), keep=("run",)),
    Case("shared-resume-with-flag", ("tune", "--resume", "run", "--shared", "--no-progress"),
         ("--resume", "--shared"), keep=("run",)),
    Case("shared-incompatible-cameras", ("tune", S, "big.yaml", "--shared", *NEW),
         ("big.yaml", "640x480", "sensor size"),
         setup=_variant("big.yaml", {"camera.image_size": [640, 480]})),
    Case("shared-bad-second-scene", ("tune", S, "b.yaml", "--shared", *NEW), ("b.yaml",),
         setup=_junk("b.yaml")),
    Case("shared-aggregate-without-shared", ("tune", S, "--aggregate", "min", *NEW),
         ("--aggregate", "--shared")),
    Case("shared-aggregate-bad", ("tune", S, "b.yaml", "--shared", "--aggregate", "quantile 2",
                                  *NEW), ("--aggregate", "quantile 2"), setup=_variant()),
    Case("shared-resume-changed-scene", ("tune", "--resume", "shared", "--no-progress"),
         ("b.yaml", "changed"), setup=_changed_shared_run, keep=("shared",)),
    Case("shared-resume-bad-stored-aggregate", ("tune", "--resume", "shared", "--no-progress"),
         ("run.sqlite", "aggregate", "max"), setup=_bad_aggregate_run, keep=("shared",)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_shared_flag_is_one_line(case, case_dir):
    check_case(case, case_dir)
    if case.id in ("shared-one-scene", "shared-incompatible-cameras"):
        assert not (case_dir / "new").exists()  # refused before anything is written
