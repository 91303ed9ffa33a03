"""A station run: capture files in, one output folder out (``rvmsim eol``).

:func:`run_station` checks every input first (the scene's ``eol`` section and the target in
view, the compensation law, every capture readable and of the camera's size), then runs the
station's step on each car (:meth:`~.station.Station.car`), writing its files into a staging
folder (:class:`~.outputs.Staging`), then ``eol.json``, ``eol.csv`` and the page; only then
are the files moved into the output folder.  An error anywhere leaves the output folder as
it was (a failing car is not an error: it is a row).
"""

from __future__ import annotations

import contextlib
import dataclasses
import time
from collections.abc import Callable, Generator, Sequence
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import TYPE_CHECKING

from .._procs import start_pool, stop_pool, stop_requested
from .._progress import progress_bar
from ..errors import RvmsimError
from ..render import RenderProcess
from ..scene import Scene
from ..pose import capture_folders, check_captures, load_capture
from .outputs import Staging, output_lock, write_car, write_tables
from .records import CarResult, StationResult
from .station import Station, StationSettings

if TYPE_CHECKING:
    from .._progress import ProgressBar

__all__ = ["run_station", "car_names"]


def car_names(captures: Sequence[Path]) -> list[str]:
    """The stem of each capture's output files: its file's stem, numbered when met again
    (``front``, ``front_2``, …), as :func:`rvmsim.validate.capture_folders` names folders."""
    return [p.name for p in capture_folders(captures, Path("."))]


#: The station of a worker process (made once per worker by :func:`_init_worker`).
_WORKER: Station | None = None


def _init_worker(scene: Scene, settings: StationSettings) -> None:
    global _WORKER
    _WORKER = Station(scene, settings)
    _WORKER.prepare()


def _work(path: Path, name: str) -> CarResult:
    """One car in a worker process."""
    assert _WORKER is not None  # set by the pool's initializer
    return _WORKER.car(load_capture(path, _WORKER.scene.fisheye_camera()), str(path), name)


def _cars(station: Station, captures: Sequence[Path], names: Sequence[str],
          workers: int) -> Generator[CarResult, None, None]:
    """Each car's result, in order: in this process, or on ``workers`` worker processes
    (each sets up its own station)."""
    if workers <= 1:
        station.prepare()
        cam = station.scene.fisheye_camera()
        for path, name in zip(captures, names):
            yield station.car(load_capture(path, cam), str(path), name)
        return
    pool = start_pool(workers, initializer=_init_worker, initargs=(station.scene,
                                                                  station.settings))
    done = False
    try:
        futures = [pool.submit(_work, p, n) for p, n in zip(captures, names)]
        for fut in futures:
            try:
                yield fut.result()
            except BrokenProcessPool as err:  # a worker died, or its state did not unpickle
                # (or a SIGTERM to the process group ended it)
                raise stop_requested() or RvmsimError(
                    f"station worker processes failed ({err}); run with --workers 1 to see "
                    "the error in this process") from None
        done = True
    finally:
        stop_pool(pool, now=not done)


def _bar(total: int, progress: bool) -> ProgressBar | None:
    if not progress:
        return None

    bar: ProgressBar = progress_bar(total=total, desc="eol", unit="car", leave=False)
    return bar


def run_station(scene: Scene, captures: Sequence[Path], out: str | Path,
                settings: StationSettings, *, params_file: str = "",
                write_page: Callable[[StationResult, Path], Path] | None = None,
                workers: int = 1, progress: bool = False,
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
        :mod:`.outputs`), all moved in at the end; the files of the station run that
        was there before (its ``eol.json`` names them) are replaced, other files are left.
        One station run at a time writes into a folder (its lock, ``eol.lock``).
    settings : StationSettings
    params_file : str
        The platform setting's file, for the record.
    write_page : callable, optional
        ``write_page(result, folder)`` writes the HTML page into ``folder`` and returns its
        path (:func:`rvmsim.report.write_eol_page`).
    workers : int
        Processes the cars are shared out to (:func:`rvmsim._procs.start_pool`; each sets
        up its own station, so at most one per two cars is used); 1: in this process.
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
        over then.  Another process's station run writing into ``out``.
    """
    t0 = time.perf_counter()
    output_lock(out).check_free()  # another station run writing there: say so before the work
    captures = [Path(p) for p in captures]
    # every capture read once before anything is written: a missing, unreadable, corrupt
    # or blank file, or one of another size than the camera's, is an error naming it
    check_captures(captures, scene.fisheye_camera())
    station = Station(scene, settings, progress=progress)
    t_setup = time.perf_counter() - t0
    names = car_names(captures)
    with output_lock(out):  # one station run at a time per output folder
        return _run_into(station, captures, names, Staging(out), settings, params_file,
                         write_page, workers, progress, on_car, t0, t_setup)


def _run_into(station: Station, captures: list[Path], names: list[str], staging: Staging,
              settings: StationSettings, params_file: str,
              write_page: Callable[[StationResult, Path], Path] | None, workers: int,
              progress: bool, on_car: Callable[[CarResult], None] | None, t0: float,
              t_setup: float) -> StationResult:
    """:func:`run_station`'s cars, written into ``staging`` and committed."""
    bar = _bar(len(captures), progress)
    cars: list[CarResult] = []
    try:
        # a car's renders (its pose search, its labels) in one render worker for the
        # whole station, where the cars are not shared out to processes
        with RenderProcess(), contextlib.closing(_cars(station, captures, names,
                                                       min(workers, len(captures) // 2))
                                                 ) as results:
            for car in results:
                files = write_car(car, staging.dir, settings.output)
                cars.append(dataclasses.replace(
                    car, images={}, files=files,
                    guidelines=None if car.guidelines is None else car.guidelines.written()))
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
