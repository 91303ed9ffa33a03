"""``rvmsim calibrate`` as one call: a calibration from board captures, or an existing one
imported, written into an output folder, with the scene's camera block and a summary."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import yaml
from pydantic import ValidationError

from ..errors import RvmsimError
from ..scene import CameraSpec, camera_problem
from ..pose import check_captures
from ..storage import staged_folder, write_text
from .board import BoardSpec, CalibrationInputError, parse_board_spec
from .captures import board_images, load_grey
from .counting import HINT_CAPTURES, counting_hint, other_counting
from .detect import find_board_view
from .imports import MAX_FIT_RMS_PX, fit_error_text, import_calibration
from .intrinsics import MIN_VIEWS, BoardView, calibrate_fisheye
from .outputs import camera_block, write_calibration_outputs

__all__ = ["CalibrationSummary", "calibrate_captures", "import_camera"]


@dataclass(frozen=True)
class CalibrationSummary:
    """What a calibration gives the user.

    Attributes
    ----------
    camera : dict
        The scene's ``camera`` keys (:func:`~.outputs.camera_block`), written to
        ``camera.yaml`` and, on request, into a scene (:func:`~.outputs.write_scene_camera`).
    text : str
        For the terminal: what was found or imported, and how well it fits.
    warnings : tuple of str
        One line each, for stderr: what was written although it is doubtful (an OCamCalib
        fit over :data:`~.imports.MAX_FIT_RMS_PX` accepted with ``accept_fit_error``).
    """

    camera: dict[str, Any]
    text: str
    warnings: tuple[str, ...] = ()


def calibrate_captures(captures: Sequence[str | Path], board_spec: str, out: str | Path,
                       fov_deg: float | None = None) -> CalibrationSummary:
    """Find the board in every capture (images, or folders of them), calibrate the fisheye
    intrinsics and write ``calibration.json``, ``coverage.png`` and ``camera.yaml`` into
    ``out`` (:func:`~.outputs.write_calibration_outputs`).

    Parameters
    ----------
    captures : sequence of path
        Image files, or folders standing for their images.
    board_spec : str
        The board (:func:`~.board.parse_board_spec`: ``COLSxROWS:SQUARE``, ``charuco:…`` or a
        scene file).
    out : path
        Output folder (created).
    fov_deg : float, optional
        The lens's field, degrees, for the camera block.

    Raises
    ------
    RvmsimError
        One line: a bad board spec, an unreadable capture, captures of different sizes, or
        too few usable views.
    """

    board = parse_board_spec(board_spec)
    files = board_images(list(captures))
    size = _check_captures(files)
    views, missed = _find_views(files, board, board_spec)
    calib = calibrate_fisheye(views, board, size)
    write_calibration_outputs(calib, views, board, out, fov_deg)
    used = sum(v.used for v in calib.views)
    dropped = [(v.name, len(v.dropped)) for v in calib.views if v.used and v.dropped]
    k = calib.K
    text = (f"board found in {len(views)} of {len(files)} captures"
            + (f" (not in: {', '.join(missed[:5])}{', …' if len(missed) > 5 else ''})"
               if missed else "")
            + f"; {used} views used, {len(views) - used} rejected as outliers"
            + (f"; {sum(n for _, n in dropped)} outlier corners dropped in {len(dropped)} "
               f"used views ({', '.join(f'{v}: {n}' for v, n in dropped[:8])}"
               f"{', …' if len(dropped) > 8 else ''})" if dropped else "") + "\n"
            f"fx {k[0, 0]:.3f}  fy {k[1, 1]:.3f}  cx {k[0, 2]:.3f}  cy {k[1, 2]:.3f} px; "
            f"D {', '.join(f'{d:+.6f}' for d in calib.D)}; RMS {calib.rms_px:.3f} px")
    return CalibrationSummary(camera_block(calib.K, calib.D, calib.image_size, fov_deg), text)


def _check_captures(files: list[Path]) -> tuple[int, int]:
    """Every capture read once before any detection (:func:`rvmsim.validate.check_captures`):
    a missing, unreadable, corrupt or blank one is refused naming it, and so are captures
    of different sizes.  Returns their (width, height), px.

    Raises
    ------
    RvmsimError
        One line naming the capture at fault, or the sizes met.
    """

    sizes = check_captures(files)
    if len(set(sizes)) > 1:
        first = files[sizes.index(sizes[0])]
        other = next(k for k, s in enumerate(sizes) if s != sizes[0])
        raise RvmsimError(f"{files[other]}: capture is {sizes[other][0]}x{sizes[other][1]} px "
                          f"but {first.name} is {sizes[0][0]}x{sizes[0][1]} px (captures "
                          "differ in size: one camera per run)")
    return sizes[0]


def _find_views(files: list[Path], board: BoardSpec, spec: str
                ) -> tuple[list[BoardView], list[str]]:
    """The board's views in ``files`` (captures of one size, :func:`_check_captures`) and
    the names of the captures without it.  A checkerboard found in none of the first
    :data:`~.counting.HINT_CAPTURES` captures, or in fewer than
    :data:`~.intrinsics.MIN_VIEWS` in all, is looked for with the other counting
    (:func:`~.counting.other_counting`); when that finds it, the error says so at once.

    Raises
    ------
    RvmsimError
        The board (maybe) miscounted; too few views.
    """

    views: list[BoardView] = []
    missed: list[str] = []
    missed_greys: list[np.ndarray] = []
    tried = board.charuco is not None  # ChArUco: markers, no counting to get wrong

    def hint(where: str) -> None:
        found = other_counting(missed_greys, board)
        if found is not None:
            raise RvmsimError(f"--board {spec}: board not found in {where}; "
                              + counting_hint(board, found, spec))

    for k, f in enumerate(files):
        grey = load_grey(f)
        view = find_board_view(grey, board, f.name)
        if view is None:
            missed.append(f.name)
            if len(missed_greys) < HINT_CAPTURES:
                missed_greys.append(grey)
        else:
            views.append(view)
        if not tried and not views and k + 1 == min(HINT_CAPTURES, len(files)):
            tried = True
            hint(f"the first {k + 1} captures")
    if len(views) < MIN_VIEWS:
        if not tried:
            hint(f"{len(missed)} of {len(files)} captures")
        raise RvmsimError(f"calibration needs the board, {board.describe()}, found in at "
                          f"least {MIN_VIEWS} captures (found in {len(views)} of "
                          f"{len(files)})")
    return views, missed


def import_camera(file: str | Path, out: str | Path, fov_deg: float | None = None, *,
                  accept_fit_error: bool = False) -> CalibrationSummary:
    """Import an existing calibration (:func:`~.imports.import_calibration`: OpenCV, Kalibr,
    OCamCalib or a camera block) and write its camera block as ``out/camera.yaml``.

    Parameters
    ----------
    file : path
        The calibration file.
    out : path
        Output folder (created; nothing is written when the import is refused).
    fov_deg : float, optional
        The lens's field, degrees, for the camera block.
    accept_fit_error : bool
        Write an OCamCalib model whose Kannala-Brandt fit is worse than
        :data:`~.imports.MAX_FIT_RMS_PX` px RMS (with a warning) instead of refusing it.

    Raises
    ------
    RvmsimError
        One line naming the file: unreadable, of no known format, an unusable camera,
        without an image size, or an OCamCalib fit over the limit (without
        ``accept_fit_error``).
    """

    file, out = Path(file), Path(out)
    cam = import_calibration(file)
    warnings: tuple[str, ...] = ()
    if cam.fit_rms_px > MAX_FIT_RMS_PX:
        if not accept_fit_error:
            raise CalibrationInputError(str(file), "polynomial", f"{fit_error_text(cam)}; "
                                        "--accept-fit-error writes it anyway")
        warnings = (f"{file}: polynomial: {fit_error_text(cam)}; written as asked "
                    "(--accept-fit-error)",)
    if cam.image_size is None:
        raise CalibrationInputError(str(file), "resolution" if cam.source_format == "opencv"
                                    else "", "the calibration gives no image size")
    block = camera_block(cam.K, cam.D, cam.image_size, fov_deg)
    try:  # what a scene's camera must be: a camera that passed the import's checks is
        spec = CameraSpec.model_validate({**block, "mount": {"position": [0.0, 0.0, 0.0]}})
    except ValidationError as err:
        raise CalibrationInputError(str(file), "", "not usable as a scene's camera: "
                                    f"{err.errors()[0]['msg']}") from None
    problem = camera_problem(spec)
    if problem is not None:
        raise CalibrationInputError(str(file), problem[0], problem[1])
    with staged_folder(out) as stage:  # moved in when written
        write_text(stage / "camera.yaml", f"# rvmsim calibrate --import {file.name} "
                   f"({cam.source_format})\n"
                   + yaml.safe_dump({"camera": block}, sort_keys=False, default_flow_style=None))
    text = f"imported {file} ({cam.source_format})"
    if cam.source_format == "ocamcalib":
        text += (f"; Kannala-Brandt fit error RMS {cam.fit_rms_px:.3f} px, "
                 f"max {cam.fit_max_px:.3f} px")
    return CalibrationSummary(block, text, warnings)
