"""Bad flags and inputs of robust tuning (`rvmsim tune SCENE --robust`): one stderr line
naming the option or the file, exit status 2, no traceback, the finished run unchanged."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE, small_scene
from .harness import ENDLESS, Case, check_case

S = SMALL_SCENE
NEW = ("--out", "new", "--no-progress", "--workers", "1", "--budget", "4")


def _no_variation(folder):
    small_scene(folder, {"variation": None})


def _bad_variation_file(folder):
    (folder / "v.yaml").write_text("mount:\n  yaw_deg: {uniform: {half_width: -1}}\n")


CASES = [
    Case("robust-samples-without-robust", ("tune", S, "--samples", "4", *NEW), ("--samples",)),
    Case("robust-variation-without-robust", ("tune", S, "--variation", "v.yaml", *NEW),
         ("--variation",)),
    Case("robust-samples-zero", ("tune", S, "--robust", "--samples", "0", *NEW),
         ("--samples",)),
    Case("robust-samples-too-many", ("tune", S, "--robust", "--samples", "100000", *NEW),
         ("--samples",), isolate=ENDLESS),
    Case("robust-with-resume", ("tune", "--robust", "--resume", "run", "--no-progress"),
         ("--resume",), keep=("run",)),
    Case("robust-scene-without-variation", ("tune", S, "--robust", *NEW),
         (S, "variation"), _no_variation),
    Case("robust-variation-file-missing", ("tune", S, "--robust", "--variation", "none.yaml",
                                           *NEW), ("none.yaml",)),
    Case("robust-variation-file-bad", ("tune", S, "--robust", "--variation", "v.yaml", *NEW),
         ("v.yaml", "yaw_deg"), _bad_variation_file),
    Case("robust-aggregate-bad", ("tune", S, "--robust", "--aggregate", "median", *NEW),
         ("--aggregate",)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_robust_input(case, case_dir):
    check_case(case, case_dir)
