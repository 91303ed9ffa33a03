"""Bad flags of every command (issue #14, group 8): each is one stderr line naming the
command's option (or the file), exit status 2, no traceback, and the stored run given to the
command byte-identical afterwards.

Here are the values our own option types and commands refuse.  click's own usage errors (a
word for a number, a required argument or option not given, a value given to a flag, an
extra argument) are one class each, checked once in tests/test_cli.py
(``test_usage_errors_are_one_line_naming_the_option``)."""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import pytest

from .conftest import SMALL_SCENE
from ..cli_runner import run_in_process
from .harness import DASK, MEMORY, Case, check_case

RUN = ("run",)


def _file(name: str, text: str = "x\n"):
    """A setup writing a regular file ``name`` (an output path that is not a folder, or a
    folder path under a file)."""
    def setup(folder: Path) -> None:
        (folder / name).write_text(text)
    return setup


def _folder(name: str):
    def setup(folder: Path) -> None:
        (folder / name).mkdir()
    return setup


_CAPTURES: list[Path] = []  # the one rendered capture, made by the first case that needs it


def _capture(folder: Path) -> None:
    """A real capture of the small scene, ``cap/fisheye_color.png``: its rendered fisheye
    colour image (rendered once per test session)."""
    if not _CAPTURES:
        made = Path(tempfile.mkdtemp(prefix="rvmsim-capture-"))
        shutil.copy(folder / SMALL_SCENE, made / SMALL_SCENE)
        out = run_in_process(["render", SMALL_SCENE, "--out", "cap", "--no-progress"], cwd=made)
        assert out.code == 0, out.stderr
        _CAPTURES.append(made / "cap")
    shutil.copytree(_CAPTURES[0], folder / "cap")


def _sweep(folder: Path) -> None:
    """A valid two-point sweep of the small scene."""
    (folder / "sweep.yaml").write_text(
        "name: flags\nbase_scene: scene.yaml\naxes:\n  pitch_deg: [25, 30]\n"
        "tune: {strategy: random, budget: 8, config: {output: {size: [160, 90]}}}\n")


def _both(*setups):
    def setup(folder: Path) -> None:
        for s in setups:
            s(folder)
    return setup


S = SMALL_SCENE
CAP = "cap/fisheye_color.png"
NOT_A_FOLDER = _file("blocker")
LONG = "x" * 300  # a file name longer than any file system allows: OSError on writing

CASES = [
    # ---- no command, unknown command, global options
    Case("no-command", (), ("command",)),
    Case("unknown-command", ("rander", S), ("rander",)),
    Case("unknown-global-option", ("--verbose", "render"), ("--verbose",)),
    # ---- render
    Case("render-missing-scene", ("render", "--out", "r"), ("render", "SCENE")),
    Case("render-missing-out", ("render", S), ("render", "--out")),
    Case("render-out-no-value", ("render", S, "--out"), ("render", "--out")),
    Case("render-unknown-option", ("render", S, "--out", "r", "--sacle", "0.5"), ("--sacle",)),
    Case("render-extra-argument", ("render", S, "other.yaml", "--out", "r"), ("other.yaml",)),
    Case("render-scale-nan", ("render", S, "--out", "r", "--scale", "nan"), ("--scale",)),
    Case("render-scale-word", ("render", S, "--out", "r", "--scale", "half"), ("--scale",)),
    Case("render-scale-big", ("render", S, "--out", "r", "--scale", "40"), ("--scale",),
         isolate=MEMORY),
    Case("render-face-size-small", ("render", S, "--out", "r", "--face-size", "2"),
         ("--face-size",)),
    Case("render-face-size-float", ("render", S, "--out", "r", "--face-size", "64.5"),
         ("--face-size",)),
    Case("render-out-is-file", ("render", S, "--out", "blocker"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("render-out-under-file", ("render", S, "--out", "blocker/sub"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("render-scene-missing", ("render", "nope.yaml", "--out", "r"), ("nope.yaml",)),
    Case("render-scene-is-folder", ("render", "run", "--out", "r"), ("run",), keep=RUN),
    Case("render-face-size-big", ("render", S, "--out", "r", "--face-size", "8192"),
         ("--face-size",), isolate=MEMORY),
    Case("render-out-name-too-long", ("render", S, "--out", LONG, "--no-progress"), (LONG,)),
    Case("render-progress-value", ("render", S, "--out", "r", "--progress=yes"),
         ("--progress",)),
    # ---- process
    Case("process-scale-inf", ("process", S, "--out", "p", "--scale", "inf"), ("--scale",)),
    Case("process-scale-negative", ("process", S, "--out", "p", "--scale", "-0.5"),
         ("--scale",)),
    Case("process-scale-shrinks-rad", ("process", S, "--out", "p", "--scale", "0.05"),
         ("--scale",)),  # RAD follows the scale: 640 px x 0.05 is below its 50 px
    Case("process-params-missing", ("process", S, "--out", "p", "--params", "nope.yaml"),
         ("nope.yaml",)),
    Case("process-params-folder", ("process", S, "--out", "p", "--params", "run"), ("run",),
         keep=RUN),
    Case("process-out-is-file", ("process", S, "--out", "blocker"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    # ---- evaluate
    Case("evaluate-out-is-file", ("evaluate", S, "--out", "blocker"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("evaluate-out-under-file", ("evaluate", S, "--out", "blocker/sub/deeper"),
         ("--out", "blocker"), setup=NOT_A_FOLDER),
    Case("evaluate-scale-nan", ("evaluate", S, "--scale", "NaN"), ("--scale",)),
    Case("evaluate-params-folder", ("evaluate", S, "--params", "run"), ("run",), keep=RUN),
    Case("evaluate-scale-grows-rad", ("evaluate", S, "--scale", "4"), ("--scale",)),
    Case("evaluate-criteria-missing", ("evaluate", S, "--criteria", "nope.yaml"),
         ("nope.yaml",)),
    # ---- tune
    Case("tune-max-time-nan", ("tune", S, "--out", "t", "--max-time", "nan"), ("--max-time",)),
    Case("tune-max-time-inf", ("tune", S, "--out", "t", "--max-time", "inf"), ("--max-time",)),
    Case("tune-max-time-negative", ("tune", S, "--out", "t", "--max-time", "-5"),
         ("--max-time",)),
    Case("tune-max-time-overflow", ("tune", S, "--out", "t", "--max-time", "1e400"),
         ("--max-time",)),
    Case("tune-target-score-nan", ("tune", S, "--out", "t", "--target-score", "nan"),
         ("--target-score",)),
    Case("tune-target-score-big", ("tune", S, "--out", "t", "--target-score", "1.5"),
         ("--target-score",)),
    Case("tune-budget-zero", ("tune", S, "--out", "t", "--budget", "0"), ("--budget",)),
    Case("tune-workers-zero", ("tune", S, "--out", "t", "--workers", "0"), ("--workers",)),
    Case("tune-workers-huge", ("tune", S, "--out", "t", "--workers", "1" + "0" * 30),
         ("--workers",)),
    Case("tune-seed-negative", ("tune", S, "--out", "t", "--seed", "-1"), ("--seed",)),
    Case("tune-seed-huge", ("tune", S, "--out", "t", "--seed", str(2**64)), ("--seed",)),
    Case("tune-seed-float", ("tune", S, "--out", "t", "--seed", "1.5"), ("--seed",)),
    Case("tune-strategy-unknown", ("tune", S, "--out", "t", "--strategy", "annealing"),
         ("--strategy",)),
    Case("tune-out-is-file", ("tune", S, "--out", "blocker"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("tune-out-under-file", ("tune", S, "--out", "blocker/run"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("tune-out-name-too-long", ("tune", S, "--out", LONG, "--no-progress"), (LONG,)),
    Case("tune-criteria-missing", ("tune", S, "--out", "t", "--criteria", "nope.yaml"),
         ("nope.yaml",)),
    Case("tune-config-missing", ("tune", S, "--out", "t", "--config", "nope.yaml"),
         ("nope.yaml",)),
    Case("tune-config-folder", ("tune", S, "--out", "t", "--config", "run"), ("run",),
         keep=RUN),
    Case("tune-resume-max-time-nan", ("tune", "--resume", "run", "--max-time", "nan"),
         ("--max-time",), keep=RUN),
    Case("tune-resume-workers-zero", ("tune", "--resume", "run", "--workers", "0"),
         ("--workers",), keep=RUN),
    Case("tune-resume-target-score-nan", ("tune", "--resume", "run", "--target-score", "nan"),
         ("--target-score",), keep=RUN),
    Case("tune-resume-is-file", ("tune", "--resume", "blocker"), ("blocker",),
         setup=NOT_A_FOLDER),
    Case("tune-existing-run", ("tune", S, "--out", "run", "--no-progress"), ("--resume",),
         keep=RUN),
    # ---- batch
    Case("batch-seed-negative", ("batch", S, "--out", "b", "--seed", "-3"), ("--seed",)),
    Case("batch-workers-zero", ("batch", S, "--out", "b", "--workers", "0"), ("--workers",)),
    Case("batch-out-is-file", ("batch", S, "--out", "blocker"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("batch-scheduler-not-an-address", ("batch", S, "--out", "b", "--scheduler", "cluster"),
         ("--scheduler",)),
    Case("batch-config-missing", ("batch", S, "--out", "b", "--config", "nope.yaml"),
         ("nope.yaml",)),
    Case("batch-out-under-file", ("batch", S, "--out", "blocker/runs"), ("--out", "blocker"),
         setup=NOT_A_FOLDER),
    Case("batch-scheduler-unreachable",  # progress bars on: no bar above the error (10 s)
         ("batch", S, "--out", "b", "--scheduler", "tcp://127.0.0.1:1"), ("tcp://127.0.0.1:1",),
         isolate=DASK),
    Case("batch-strategy-unknown", ("batch", S, "--strategy", "grid"), ("--strategy",)),
    # ---- status
    Case("status-top-zero", ("status", "run", "--top", "0"), ("status", "--top"), keep=RUN),
    # ---- select
    Case("select-rank-zero", ("select", "run", "--rank", "0"), ("select", "--rank"), keep=RUN),
    Case("select-out-is-folder", ("select", "run", "--out", "exports"), ("--out", "exports"),
         setup=_folder("exports"), keep=RUN),
    Case("select-out-under-file", ("select", "run", "--out", "blocker/p.yaml"),
         ("--out", "blocker"), setup=NOT_A_FOLDER, keep=RUN),
    Case("select-out-name-too-long", ("select", "run", "--out", LONG), (LONG,), keep=RUN),
    # ---- report
    Case("report-out-is-folder", ("report", "run", "--out", "pages"), ("--out", "pages"),
         setup=_folder("pages"), keep=RUN),
    Case("report-out-under-file", ("report", "run", "--out", "blocker/r.html"),
         ("--out", "blocker"), setup=NOT_A_FOLDER, keep=RUN),
    Case("report-out-name-too-long", ("report", "run", "--out", LONG), (LONG,), keep=RUN),
    Case("report-path-missing", ("report", "nothing"), ("nothing",)),
    # ---- validate
    Case("validate-capture-missing", ("validate", S, "--capture", "nope.png"), ("nope.png",)),
    Case("validate-capture-folder", ("validate", S, "--capture", "run"), ("run",), keep=RUN),
    Case("validate-max-angle-nan", ("validate", S, "--capture", CAP, "--max-angle-deg", "nan"),
         ("--max-angle-deg",), setup=_capture),
    Case("validate-search-px-nan", ("validate", S, "--capture", CAP, "--search-px", "nan"),
         ("--search-px",), setup=_capture),
    Case("validate-max-rms-zero", ("validate", S, "--capture", CAP, "--max-rms-px", "0"),
         ("--max-rms-px",), setup=_capture),
    Case("validate-max-rms-nan", ("validate", S, "--capture", CAP, "--max-rms-px", "nan"),
         ("--max-rms-px",), setup=_capture),
    Case("validate-max-position-inf",
         ("validate", S, "--capture", CAP, "--max-position-mm", "inf"),
         ("--max-position-mm",), setup=_capture),
    Case("validate-max-chamfer-nan",
         ("validate", S, "--capture", CAP, "--max-chamfer-px", "nan"),
         ("--max-chamfer-px",), setup=_capture),
    Case("validate-min-landmarks-few", ("validate", S, "--capture", CAP, "--min-landmarks", "3"),
         ("--min-landmarks",), setup=_capture),
    Case("validate-params-missing", ("validate", S, "--capture", CAP, "--params", "nope.yaml"),
         ("nope.yaml",), setup=_capture),
    Case("validate-write-scene-under-file",
         ("validate", S, "--capture", CAP, "--write-scene", "blocker/s.yaml"),
         ("--write-scene", "blocker"), setup=_both(_capture, NOT_A_FOLDER)),
    Case("validate-out-is-file", ("validate", S, "--capture", CAP, "--out", "blocker"),
         ("--out", "blocker"), setup=_both(_capture, NOT_A_FOLDER)),
    Case("validate-write-scene-folder",
         ("validate", S, "--capture", CAP, "--write-scene", "cap"), ("--write-scene", "cap"),
         setup=_capture),
    # ---- sweep
    Case("sweep-workers-zero", ("sweep", "sweep.yaml", "--workers", "0"), ("--workers",),
         setup=_sweep),
    Case("sweep-out-is-file", ("sweep", "sweep.yaml", "--out", "blocker"), ("--out", "blocker"),
         setup=_both(_sweep, NOT_A_FOLDER)),
    Case("sweep-scheduler-not-an-address", ("sweep", "sweep.yaml", "--scheduler", "here:"),
         ("--scheduler",), setup=_sweep),
    Case("sweep-file-missing", ("sweep", "nope.yaml"), ("nope.yaml",)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_flag_is_one_line(case, case_dir):
    check_case(case, case_dir)


def test_case_ids_are_unique():
    assert len({c.id for c in CASES}) == len(CASES)
