"""``rvmsim eol``: the end-of-line station, on one capture of its target per car."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .errors import Command
from .params import FiniteFloat, Integer, OutputFolder, load_isp

__all__ = ["eol"]


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), required=True,
              help="ISP params file: the platform setting (full sensor).")
@click.option("--capture", "capture_paths", type=click.Path(path_type=Path), required=True,
              multiple=True,
              help="One car's capture of the station's target (PNG/JPEG/TIFF, the camera's "
                   "full image size), or a folder of them; repeat for several cars.")
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--compensation", default="default", show_default=True,
              help="Compensation file (what the EOL step writes, its ranges, the load state "
                   "measured at), or 'default'.")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--variation", "variation_file", type=click.Path(path_type=Path), default=None,
              help="Variation file holding the load state the compensation's "
                   "station.measured_at names (default: the scene's variation section).")
@click.option("--min-landmarks", type=Integer(6), default=8, show_default=True,
              help="Fewer target corners matched: the car's pose is not recovered (it fails).")
@click.option("--search-px", type=FiniteFloat(2.0, 200.0), default=30.0, show_default=True,
              help="How far from its nominal place a target corner is first searched for, px.")
@click.option("--workers", type=Integer(1, 64), default=1, show_default=True,
              help="Processes the cars are shared out to (each sets up its own station; at "
                   "most one per two cars). Helps only on idle cores.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def eol(scene: Path, params_file: Path, capture_paths: tuple[Path, ...], out: Path,
        compensation: str, criteria_file: Path | None, variation_file: Path | None,
        min_landmarks: int, search_px: float, workers: int, progress: bool) -> None:
    """The end-of-line station: each car's per-car ISP values from a capture of the
    target SCENE's eol section names.

    For each capture: the camera's pose from the target's corners, its deviation from the
    nominal mount, the per-car values of the compensation law, and every EC on the car's
    corrected picture.  Writes OUT/<capture name>.yaml (the car's full ISP parameters),
    beside it <capture name>.guidelines.bin (its parking-guideline table from its measured
    pose and per-car values, when the scene's vehicle has its running gear), its pictures,
    eol.json, eol.csv and eol.html.  Exit status: 0 every car passes, 1 a
    car fails (pose not recovered, EOL range exceeded, an EC fails), 2 an error (nothing
    in OUT is written over).
    """
    from ..compensation import compensation_for
    from ..criteria import load_criteria
    from ..eol import StationSettings, run_station
    from ..pipeline import record_output
    from ..report import write_eol_page
    from ..robust import load_variation
    from ..scene import load_scene
    from ..pose import capture_files

    captures = capture_files(capture_paths)
    sc = load_scene(scene)
    params, output = load_isp(params_file, complete=True)  # never a default into a car
    model = compensation_for(compensation)
    assert model is not None  # a value is always given
    criteria = load_criteria(criteria_file)
    # every car's verdict at the RVM image of record, whatever size the file was searched at
    output = record_output(criteria, sc, output.mirror)
    settings = StationSettings(
        params, output, model, criteria,
        load_variation(variation_file) if variation_file is not None else None,
        min_landmarks, search_px)
    result = run_station(sc, captures, out, settings, params_file=str(params_file),
                         write_page=write_eol_page, workers=workers, progress=progress)
    click.echo(f"{sc.name}: EOL station, target {result.target}, load state "
               f"{result.load_state['name']}")
    click.echo(result.summary())
    n_params = sum("params" in c.files for c in result.cars)
    n_tables = sum("guidelines" in c.files for c in result.cars)
    tables = "" if result.guideline_angles is None else f", {n_tables} guideline tables"
    click.echo(f"wrote {n_params} parameter files{tables}, eol.json, eol.csv and eol.html in "
               f"{out} ({result.timings['total']:.1f} s)")
    sys.exit(0 if result.passed else 1)
