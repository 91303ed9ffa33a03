"""A station run: capture files in, one output folder out (``rvmsim eol``).

:func:`run_station` checks every input first (the scene's ``eol`` section and the target in
view, the compensation law, every capture readable and of the camera's size), then runs the
station's step on each car (:meth:`~.station.Station.car`), writing its files into a staging
folder (:class:`~.outputs.Staging`), then ``eol.json``, ``eol.csv`` and the page; only then
are the files moved into the output folder.  An error anywhere leaves the output folder as
it was (a failing car is not an error: it is a row).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from ..scene import Scene
from ..validate import capture_folders, load_capture
from .outputs import Staging, write_car, write_tables
from .records import CarResult, StationResult
from .station import Station, StationSettings

if TYPE_CHECKING:
    from .._progress import ProgressBar

__all__ = ["run_station", "car_names"]


def car_names(captures: Sequence[Path]) -> list[str]:
    """The stem of each capture's output files: its file's stem, numbered when met again
    (``front``, ``front_2``, …), as :func:`rvmsim.validate.capture_folders` names folders."""
    return [p.name for p in capture_folders(captures, Path("."))]


def _check_captures(scene: Scene, captures: Sequence[Path]) -> None:
    """Read every capture once: a missing, unreadable, corrupt or blank file, or one of
    another size than the camera's, is an error naming it (before anything is written)."""
    cam = scene.fisheye_camera()
    for path in captures:
        load_capture(path, cam)


def _bar(total: int, progress: bool) -> ProgressBar | None:
    if not progress:
        return None
    from tqdm import tqdm

    bar: ProgressBar = tqdm(total=total, desc="eol", unit="car", leave=False)
    return bar


def run_station(scene: Scene, captures: Sequence[Path], out: str | Path,
                settings: StationSettings, *, params_file: str = "",
                write_page: Callable[[StationResult, Path], Path] | None = None,
                progress: bool = False,
                on_car: Callable[[CarResult], None] | None = None) -> StationResult:
    """Run the EOL station on each car's capture and write the results into ``out``.

    Parameters
    ----------
    scene : Scene
        The car as designed, its test site (the ECs) and its ``eol`` section.
    captures : sequence of Path
        One capture of the station's target per car (:func:`rvmsim.validate.capture_files`
        expands folders).
    out : path
        Output folder (created when missing): per car ``<name>.yaml`` and its pictures,
        ``eol.json``, ``eol.csv`` and (with ``write_page``) ``eol.html`` (see
        :mod:`.outputs`).  Files of the same names are written over; others are left.
    settings : StationSettings
    params_file : str
        The platform setting's file, for the record.
    write_page : callable, optional
        ``write_page(result, folder)`` writes the HTML page into ``folder`` and returns its
        path (:func:`rvmsim.report.write_eol_page`).
    progress : bool
        A progress bar over the cars.
    on_car : callable, optional
        Called with each car's result as soon as it is known.

    Returns
    -------
    StationResult
        Each car's result (without its pictures, which are in the files).

    Raises
    ------
    RvmsimError
        A bad ``eol`` section or target not in view (:class:`~rvmsim.errors.SceneError`),
        a bad compensation model, an unreadable capture or one of the wrong size, or a file
        that cannot be written: one line naming the file.  Nothing in ``out`` is written
        over then.
    """
    t0 = time.perf_counter()
    captures = [Path(p) for p in captures]
    _check_captures(scene, captures)
    station = Station(scene, settings, progress=progress)
    station.prepare()
    t_setup = time.perf_counter() - t0
    names = car_names(captures)
    cam = scene.fisheye_camera()
    staging = Staging(out)
    bar = _bar(len(captures), progress)
    cars: list[CarResult] = []
    try:
        for path, name in zip(captures, names):
            car = station.car(load_capture(path, cam), str(path), name)
            files = write_car(car, staging.dir, settings.output)
            cars.append(dataclasses.replace(car, images={}, files=files))
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(f"{sum(c.passed for c in cars)} pass")
            if on_car is not None:
                on_car(cars[-1])
        t_cars = time.perf_counter() - t0 - t_setup
        result = station.result(cars, params_file,
                                {"setup": t_setup, "cars": t_cars,
                                 "total": time.perf_counter() - t0})
        write_tables(result, staging.dir)
        if write_page is not None:
            write_page(result, staging.dir)
        staging.commit()
    except BaseException:
        staging.discard()
        raise
    finally:
        if bar is not None:
            bar.close()
    return result
