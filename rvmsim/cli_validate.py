"""``rvmsim validate``: a scene against one or several real captures of its camera.

Its own module (cli.py is at its size limit); cli.py adds the command to
:data:`rvmsim.cli.cli`.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click

from .cli_params import FiniteFloat, Integer, OutputFile, OutputFolder
from .cli_params import fail as _fail
from .cli_params import fail_os as _fail_os
from .cli_params import load_isp as _load_isp
from .errors import RvmsimError

__all__ = ["validate", "capture_files"]

#: File endings of the captures a folder given to --capture holds.
CAPTURE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff")


def capture_files(paths: tuple[Path, ...]) -> list[Path]:
    """The capture files: each path given, or the images (:data:`CAPTURE_SUFFIXES`, sorted
    by name) in each folder given.

    Raises
    ------
    RvmsimError
        A folder without any capture.
    """
    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            found = sorted(f for f in p.iterdir()
                           if f.is_file() and f.suffix.lower() in CAPTURE_SUFFIXES)
            if not found:
                raise RvmsimError(f"{p}: no captures ({', '.join(CAPTURE_SUFFIXES)}) in this "
                                  "folder (--capture)")
            out += found
        else:
            out.append(p)
    return out


@dataclass(frozen=True)
class _Run:
    """What every capture's validation shares."""

    scene: Any
    kwargs: dict[str, Any]


@click.command()
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--capture", "capture_paths", type=click.Path(path_type=Path), required=True,
              multiple=True,
              help="Real frame from the vehicle's rear-view camera (PNG/JPEG/TIFF, the "
                   "camera's full image size), or a folder of them; repeat for several.")
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file: also compare the RVM images and the ECs.")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file for the ECs (with --params).")
@click.option("--out", "-o", type=OutputFolder(), default=None,
              help="Output folder (default: out/<scene name>/validate).")
@click.option("--write-scene", "write_scene", type=OutputFile(), default=None,
              help="Write a copy of SCENE with the corrected mount pose here (one capture).")
@click.option("--max-rms-px", type=FiniteFloat(0, min_open=True), default=2.0,
              show_default=True, help="Landmark RMS after the pose correction, px.")
@click.option("--max-position-mm", type=FiniteFloat(0), default=30.0, show_default=True,
              help="Largest mount position correction, mm.")
@click.option("--max-angle-deg", type=FiniteFloat(0), default=0.5, show_default=True,
              help="Largest mount angle correction (yaw, pitch or roll), degrees.")
@click.option("--max-chamfer-px", type=FiniteFloat(0), default=None,
              help="Largest edge chamfer distance with the scene's pose, px (default: not judged).")
@click.option("--min-landmarks", type=Integer(6), default=8, show_default=True,
              help="Fewer matched landmarks is an error (exit 2).")
@click.option("--search-px", type=FiniteFloat(2.0, 200.0), default=30.0, show_default=True,
              help="How far from its predicted place a landmark is first searched for, px "
                   "(at most 0.6 of its square: farther, a neighbouring corner would match).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def validate(scene: Path, capture_paths: tuple[Path, ...], params_file: Path | None,
             criteria_file: Path | None, out: Path | None, write_scene: Path | None,
             max_rms_px: float, max_position_mm: float, max_angle_deg: float,
             max_chamfer_px: float | None, min_landmarks: int, search_px: float,
             progress: bool) -> None:
    """Compare SCENE's synthetic fisheye frame with real captures of its camera.

    Finds the scene's calibration board with the chessboard detector (the starting pose),
    then its checker corners (board, ground patterns) in each capture, fits the mount pose
    that explains them, compares edges, and judges the scene against the tolerances.
    One capture: writes validation.json, validation.html and PNGs in the output folder.
    Several (or a folder): the same per capture in OUT/<capture name>/, and one summary
    table (printed, summary.json, summary.csv) and one page (validation.html) for all.
    A validation that stops writes its pictures too and names the step that failed.
    Exit status: 0 every capture passes, 1 a verdict failed, 2 an error.
    """
    from .criteria import load_criteria
    from .scene import load_scene
    from .validate import Tolerances

    try:
        captures = capture_files(capture_paths)
        if write_scene is not None and len(captures) != 1:
            raise RvmsimError(f"--write-scene: takes exactly one capture ({len(captures)} "
                              "given)")
        sc = load_scene(scene)
        params, output = _load_isp(params_file) if params_file else (None, None)
        criteria = load_criteria(criteria_file) if params_file else None
    except RvmsimError as err:
        _fail(err)
    tol = Tolerances(max_rms_px=max_rms_px, max_position_mm=max_position_mm,
                     max_angle_deg=max_angle_deg, max_chamfer_px=max_chamfer_px,
                     min_landmarks=min_landmarks)
    run = _Run(sc, dict(params=params, output=output, criteria=criteria, tolerances=tol,
                        search_px=search_px, progress=progress))
    out = out or Path("out") / scene.stem / "validate"
    if len(captures) == 1 and not any(p.is_dir() for p in capture_paths):
        _validate_one(run, scene, captures[0], out, write_scene)
    else:
        _validate_several(run, captures, out)


def _validate_one(run: _Run, scene: Path, capture_file: Path, out: Path,
                  write_scene: Path | None) -> None:
    """One capture: its outputs in ``out``, the summary printed; exits."""
    from .validate import ValidationFailure, write_corrected_scene

    try:
        try:
            result, written = _validated(run, capture_file, out)
        except ValidationFailure as fail:
            raise RvmsimError(f"{fail}; pictures in {out}") from None
        if write_scene is not None:
            write_corrected_scene(scene, result.correction, write_scene)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    click.echo(f"{run.scene.name} vs {capture_file}")
    click.echo(result.summary())
    click.echo(f"wrote {written[1]} and {len(written) - 2} PNGs in {out}")
    if write_scene is not None:
        click.echo(f"wrote the scene with the corrected mount to {write_scene}")
    sys.exit(0 if result.passed else 1)


def _validated(run: _Run, capture_file: Path, out: Path) -> tuple[Any, list[Path]]:
    """One capture loaded, validated and its outputs written into ``out``: (the
    Validation, the files written).  A ValidationFailure is raised again once its pictures
    are written (an error writing them is raised instead)."""
    from .report.validation import write_pictures, write_validation_outputs
    from .validate import ValidationFailure, load_capture
    from .validate import validate as run_validate

    capture = load_capture(capture_file, run.scene.fisheye_camera())
    try:
        result = run_validate(run.scene, capture, use_cache=True,
                              capture_name=str(capture_file), **run.kwargs)
    except ValidationFailure as fail:
        write_pictures(fail.images, out)
        raise
    return result, write_validation_outputs(result, out)


def _validate_several(run: _Run, captures: list[Path], out: Path) -> None:
    """Every capture in ``out/<capture name>/``, one summary for all; exits."""
    from .report.validation import CaptureOutcome, summary_table, write_validation_summary

    outcomes: list[CaptureOutcome] = []
    used: set[str] = set()
    for cap in captures:
        name = cap.stem
        n = 2
        while name in used:
            name, n = f"{cap.stem}_{n}", n + 1
        used.add(name)
        outcomes.append(_outcome(run, cap, out / name))
    try:
        written = write_validation_summary(outcomes, out)
    except RvmsimError as err:
        _fail(err)
    click.echo(f"{run.scene.name} vs {len(captures)} captures")
    click.echo(summary_table(outcomes))
    click.echo(f"wrote {written[2]}, {written[0].name} and {written[1].name} in {out}")
    verdicts = {o.verdict for o in outcomes}
    sys.exit(2 if "ERROR" in verdicts else 1 if "FAIL" in verdicts else 0)


def _outcome(run: _Run, capture_file: Path, out: Path) -> Any:
    """One capture of several: validated, outputs written; an error becomes its row (and a
    one-line message on stderr)."""
    from .report.validation import CaptureOutcome
    from .validate import ValidationFailure

    try:
        result, _ = _validated(run, capture_file, out)
    except ValidationFailure as fail:
        click.echo(f"rvmsim: error: {fail}; pictures in {out}", err=True)
        return CaptureOutcome(str(capture_file), out, None, str(fail), fail.step, fail.images)
    except RvmsimError as err:
        click.echo(f"rvmsim: error: {err}", err=True)
        return CaptureOutcome(str(capture_file), out, None, str(err), "error")
    except OSError as err:
        msg = f"{err.filename or out}: {err.strerror or err}"
        click.echo(f"rvmsim: error: {msg}", err=True)
        return CaptureOutcome(str(capture_file), out, None, msg, "error")
    failed = [c.name for c in result.checks if not c.passed]
    return CaptureOutcome(str(capture_file), out, result,
                          step="check: " + ", ".join(failed) if failed else "")
