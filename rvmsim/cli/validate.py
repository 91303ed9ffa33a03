"""``rvmsim validate``: a scene against one or several real captures of its camera."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

import click

from ..errors import RvmsimError
from .errors import Command
from .params import FiniteFloat, Integer, OutputFile, OutputFolder, default_folder, load_isp

if TYPE_CHECKING:
    from ..validate import CaptureOutcome

__all__ = ["validate"]


@click.command(cls=Command, error_path=("out",))
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
              callback=default_folder("scene", lambda s: Path("out") / s.stem / "validate"),
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
             criteria_file: Path | None, out: Path, write_scene: Path | None,
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
    from ..criteria import load_criteria
    from ..report import write_validation_outputs
    from ..scene import load_scene
    from ..pose import capture_files, capture_folders
    from ..validate import Tolerances, ValidationSettings, validate_captures

    captures = capture_files(capture_paths)
    several = len(captures) != 1 or any(p.is_dir() for p in capture_paths)
    if write_scene is not None and len(captures) != 1:
        raise RvmsimError(f"--write-scene: takes exactly one capture ({len(captures)} given)")
    sc = load_scene(scene)
    params, output = load_isp(params_file) if params_file else (None, None)
    criteria = load_criteria(criteria_file) if params_file else None
    tol = Tolerances(max_rms_px=max_rms_px, max_position_mm=max_position_mm,
                     max_angle_deg=max_angle_deg, max_chamfer_px=max_chamfer_px,
                     min_landmarks=min_landmarks)

    def say_error(outcome: CaptureOutcome) -> None:  # several: each error as it happens
        if outcome.result is None:
            click.echo(f"rvmsim: error: {outcome.message}", err=True)

    settings = ValidationSettings(params, output, criteria, tol, search_px)
    outcomes = validate_captures(
        sc, captures, capture_folders(captures, out) if several else [out],
        write_validation_outputs, settings, progress=progress,
        on_outcome=say_error if several else None)
    if several:
        _several(sc.name, outcomes, out)
    _one(sc.name, outcomes[0], scene, write_scene)


def _one(vehicle: str, outcome: CaptureOutcome, scene: Path, write_scene: Path | None
         ) -> NoReturn:
    """One capture: its summary printed (its error raised), the corrected scene written."""
    from ..validate import write_corrected_scene

    if outcome.result is None:
        raise RvmsimError(outcome.message)
    if write_scene is not None:
        write_corrected_scene(scene, outcome.result.correction, write_scene)
    click.echo(f"{vehicle} vs {outcome.capture}")
    click.echo(outcome.result.summary())
    click.echo(f"wrote {outcome.written[1]} and {len(outcome.written) - 2} PNGs in "
               f"{outcome.out_dir}")
    if write_scene is not None:
        click.echo(f"wrote the scene with the corrected mount to {write_scene}")
    sys.exit(0 if outcome.result.passed else 1)


def _several(vehicle: str, outcomes: list[CaptureOutcome], out: Path) -> NoReturn:
    """Several captures: the summary table printed and written."""
    from ..report.validation import summary_table, write_validation_summary

    written = write_validation_summary(outcomes, out)
    click.echo(f"{vehicle} vs {len(outcomes)} captures")
    click.echo(summary_table(outcomes))
    click.echo(f"wrote {written[2]}, {written[0].name} and {written[1].name} in {out}")
    verdicts = {o.verdict for o in outcomes}
    sys.exit(2 if "ERROR" in verdicts else 1 if "FAIL" in verdicts else 0)
