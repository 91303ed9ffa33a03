"""``rvmsim calibrate``: fisheye intrinsics from board captures, or an existing calibration
imported (``--import``); writes the scene's camera block and, with ``--write-scene``,
updates a scene's camera section."""

from __future__ import annotations

from pathlib import Path

import click

from ..errors import RvmsimError
from .errors import Command
from .params import OutputFolder

__all__ = ["calibrate"]


@click.command(cls=Command, error_path=("out",))
@click.argument("captures", nargs=-1, type=click.Path(path_type=Path))
@click.option("--board", "board_spec", metavar="SPEC",
              help="COLSxROWS:SQUARE or inner:COLSxROWS:SQUARE (INNER CORNERS across and "
                   "down, square side in m, e.g. 9x7:0.03 for a board of 10x8 squares), "
                   "squares:COLSxROWS:SQUARE (SQUARES, e.g. squares:10x8:0.03), "
                   "charuco:COLSxROWS:SQUARE:MARKER[:DICT] (a ChArUco board: SQUARES, m, a "
                   "cv2.aruco dictionary; e.g. charuco:7x10:0.08:0.06), or a scene file "
                   "whose test_site.board was used.")
@click.option("--import", "import_file", type=click.Path(path_type=Path),
              help="Import an existing calibration instead: OpenCV FileStorage YAML, Kalibr "
                   "camchain (pinhole-equidistant), OCamCalib calib_results.txt.")
@click.option("--accept-fit-error", is_flag=True,
              help="With --import of an OCamCalib model: write it even when its "
                   "Kannala-Brandt fit is worse than 1 px RMS (a warning instead of an "
                   "error).")
@click.option("-o", "--out", type=OutputFolder(), required=True,
              help="Output folder (calibration.json, coverage.png, camera.yaml).")
@click.option("--write-scene", "write_scene", type=click.Path(path_type=Path),
              help="Scene file whose camera image_size, intrinsics and lens to replace.")
@click.option("--fov-deg", type=click.FloatRange(1, 360), default=None,
              help="The lens's field (degrees) for the camera block; default: the "
                   "scene's, else 190.")
def calibrate(captures: tuple[Path, ...], board_spec: str | None, import_file: Path | None,
              accept_fit_error: bool, out: Path, write_scene: Path | None,
              fov_deg: float | None) -> None:
    """Fisheye (Kannala-Brandt) intrinsics from CAPTURES (images or folders) of a
    checkerboard, or an existing calibration imported with --import.

    Writes OUT/camera.yaml (the scene's camera block) and, from captures,
    OUT/calibration.json (K, D, RMS per view) and OUT/coverage.png.
    """
    from ..calibrate import calibrate_captures, import_camera, write_scene_camera

    if accept_fit_error and import_file is None:
        raise RvmsimError("--accept-fit-error: only with --import (an OCamCalib model's fit)")
    if import_file is not None:
        if captures:
            raise RvmsimError("give captures or --import, not both")
        done = import_camera(import_file, out, fov_deg, accept_fit_error=accept_fit_error)
    elif not captures:
        raise RvmsimError("no captures given (images or folders), nor --import FILE")
    elif board_spec is None:
        raise RvmsimError("--board is required with captures (e.g. --board 9x7:0.03, inner "
                          "corners; or squares:10x8:0.03)")
    else:
        done = calibrate_captures(captures, board_spec, out, fov_deg)
    if write_scene is not None:
        write_scene_camera(write_scene, done.camera)
    for line in done.warnings:
        click.echo(f"rvmsim: warning: {line}", err=True)
    click.echo(done.text)
    click.echo(f"wrote {out / 'camera.yaml'}"
               + (f"; updated the camera of {write_scene}" if write_scene else ""))
