"""``rvmsim calibrate``: fisheye intrinsics from board captures, or an existing calibration
imported (``--import``); writes the scene's camera block and, with ``--write-scene``,
updates a scene's camera section.

Its own module (cli.py is at its size limit); cli.py adds the command to
:data:`rvmsim.cli.cli`.
"""

from __future__ import annotations

from pathlib import Path

import click

from .cli_params import OutputFolder
from .cli_params import fail as _fail
from .cli_params import fail_os as _fail_os
from .errors import RvmsimError

__all__ = ["calibrate"]


def _from_captures(captures: tuple[Path, ...], board_spec: str | None, out: Path,
                   fov_deg: float | None) -> tuple[dict, str]:
    """Detect, calibrate, write; returns the camera block and a summary."""
    from .calibrate import (calibrate_fisheye, camera_block, capture_files, find_board_view,
                            load_grey, parse_board_spec, write_calibration_outputs)

    if board_spec is None:
        raise RvmsimError("--board is required with captures (e.g. --board 9x7:0.03)")
    board = parse_board_spec(board_spec)
    files = capture_files(list(captures))
    views, sizes, missed = [], set(), []
    for f in files:
        grey = load_grey(f)
        sizes.add((grey.shape[1], grey.shape[0]))
        view = find_board_view(grey, board, f.name)
        if view is None:
            missed.append(f.name)
        else:
            views.append(view)
    if len(sizes) > 1:
        raise RvmsimError(f"captures differ in size: {sorted(sizes)} (one camera per run)")
    calib = calibrate_fisheye(views, board, sizes.pop())
    write_calibration_outputs(calib, views, board, out, fov_deg)
    used = sum(v.used for v in calib.views)
    k = calib.K
    text = (f"board found in {len(views)} of {len(files)} captures"
            + (f" (not in: {', '.join(missed[:5])}{', …' if len(missed) > 5 else ''})"
               if missed else "")
            + f"; {used} views used, {len(views) - used} rejected as outliers\n"
            f"fx {k[0, 0]:.3f}  fy {k[1, 1]:.3f}  cx {k[0, 2]:.3f}  cy {k[1, 2]:.3f} px; "
            f"D {', '.join(f'{d:+.6f}' for d in calib.D)}; RMS {calib.rms_px:.3f} px")
    return camera_block(calib.K, calib.D, calib.image_size, fov_deg), text


def _from_import(file: Path, out: Path, fov_deg: float | None) -> tuple[dict, str]:
    import yaml

    from .calibrate import camera_block, import_calibration

    cam = import_calibration(file)
    if cam.image_size is None:
        raise RvmsimError(f"{file}: the calibration gives no image size (resolution)")
    block = camera_block(cam.K, cam.D, cam.image_size, fov_deg)
    out.mkdir(parents=True, exist_ok=True)
    (out / "camera.yaml").write_text(f"# rvmsim calibrate --import {file.name} "
                                     f"({cam.source_format})\n"
                                     + yaml.safe_dump({"camera": block}, sort_keys=False,
                                                    default_flow_style=None))
    text = f"imported {file} ({cam.source_format})"
    if cam.source_format == "ocamcalib":
        text += (f"; Kannala-Brandt fit error RMS {cam.fit_rms_px:.3f} px, "
                 f"max {cam.fit_max_px:.3f} px")
    return block, text


@click.command()
@click.argument("captures", nargs=-1, type=click.Path(path_type=Path))
@click.option("--board", "board_spec", metavar="SPEC",
              help="COLSxROWS:SQUARE (inner corners across and down, square side in m, "
                   "e.g. 9x7:0.03), charuco:COLSxROWS:SQUARE:MARKER[:DICT] (a ChArUco "
                   "board: squares, m, a cv2.aruco dictionary; e.g. charuco:7x10:0.08:0.06), "
                   "or a scene file whose test_site.board was used.")
@click.option("--import", "import_file", type=click.Path(path_type=Path),
              help="Import an existing calibration instead: OpenCV FileStorage YAML, Kalibr "
                   "camchain (pinhole-equidistant), OCamCalib calib_results.txt.")
@click.option("-o", "--out", type=OutputFolder(), required=True,
              help="Output folder (calibration.json, coverage.png, camera.yaml).")
@click.option("--write-scene", "write_scene", type=click.Path(path_type=Path),
              help="Scene file whose camera image_size, intrinsics and lens to replace.")
@click.option("--fov-deg", type=click.FloatRange(1, 360), default=None,
              help="The lens's field (degrees) for the camera block; default: the "
                   "scene's, else 190.")
def calibrate(captures: tuple[Path, ...], board_spec: str | None, import_file: Path | None,
              out: Path, write_scene: Path | None, fov_deg: float | None) -> None:
    """Fisheye (Kannala-Brandt) intrinsics from CAPTURES (images or folders) of a
    checkerboard, or an existing calibration imported with --import.

    Writes OUT/camera.yaml (the scene's camera block) and, from captures,
    OUT/calibration.json (K, D, RMS per view) and OUT/coverage.png.
    """
    from .calibrate import write_scene_camera

    try:
        if import_file is not None:
            if captures:
                raise RvmsimError("give captures or --import, not both")
            block, text = _from_import(import_file, out, fov_deg)
        elif not captures:
            raise RvmsimError("no captures given (images or folders), nor --import FILE")
        else:
            block, text = _from_captures(captures, board_spec, out, fov_deg)
        if write_scene is not None:
            write_scene_camera(write_scene, block)
    except RvmsimError as err:
        _fail(err)
    except OSError as err:
        _fail_os(err, out)
    click.echo(text)
    click.echo(f"wrote {out / 'camera.yaml'}"
               + (f"; updated the camera of {write_scene}" if write_scene else ""))
