"""What a station run writes: per car its ISP parameter file and pictures, for all cars
``eol.json`` and ``eol.csv``; all into a staging folder first (:class:`Staging`), moved
into the output folder only when the run has finished, so that an error leaves the output
folder as it was.

Files (``<name>`` is the capture's stem, numbered when two captures share one):

- ``<name>.yaml``: the car's full ISP parameter set, a params file
  (:func:`rvmsim.isp.params_to_dict`), when its pose was recovered;
- ``<name>.guidelines.bin``: beside it, the car's parking-guideline table (:mod:`.tables`),
  when the scene's vehicle has its running gear;
- ``<name>_rvm.png``: the capture through the car's parameters (its corrected picture),
  ``<name>_annotated.png``: the ECs drawn on it; a car whose pose was not recovered:
  ``<name>_landmarks.png``, ``<name>_overlay.png`` (the validation's pictures);
- ``eol.json``: :meth:`StationResult.as_dict`; ``eol.csv``: one row per car
  (:func:`csv_rows`).
"""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
import uuid
from pathlib import Path
from typing import Any

import yaml

from .._io import make_output_folder, read_json_file, write_png
from ..errors import RvmsimError
from ..isp import OutputSpec, params_to_dict
from ..scene import MOUNT_AXES
from ..storage import FolderLock, json_default, write_problem, write_text
from .records import CarResult, StationResult
from .tables import TABLE_SUFFIX

__all__ = ["Staging", "write_car", "write_tables", "csv_rows", "RESULT_FILES", "output_lock",
           "earlier_run_files", "STAGING_PREFIX"]

#: The name of a run's staging folder in the output folder begins so.
STAGING_PREFIX = ".eol-"
#: The files written for all cars, in the output folder.
RESULT_FILES = ("eol.json", "eol.csv", "eol.html")
#: A failed car's pictures that are written (of the validation's), by key.
_FAILURE_PICTURES = ("landmarks", "overlay")


class Staging:
    """A temporary folder inside ``out`` that a run writes into; :meth:`commit` moves its
    files into ``out`` (each by one rename, written over) and removes the files of the
    station run that was there before, :meth:`discard` removes it.

    Make it while holding the output folder's lock (:func:`output_lock`): staging folders
    found then (``.eol-*.tmp``) are a killed run's, and are removed.

    Raises
    ------
    RvmsimError
        ``out`` cannot be created, or the staging folder cannot be made there.
    """

    def __init__(self, out: str | Path):
        self.out = make_output_folder(out)
        for stale in self.out.glob(f"{STAGING_PREFIX}*.tmp"):
            shutil.rmtree(stale, ignore_errors=True)
        self.dir = self.out / f"{STAGING_PREFIX}{uuid.uuid4().hex[:12]}.tmp"
        try:
            self.dir.mkdir()
        except OSError as err:
            raise RvmsimError(f"{self.out}: {write_problem(err, 'cannot write here')}") from None

    def commit(self) -> list[Path]:
        """Move every staged file into the output folder, then remove the earlier run's
        files that this run did not write again (its ``eol.json`` names them); returns the
        new files' paths."""
        earlier = earlier_run_files(self.out)
        moved = []
        try:
            for f in sorted(self.dir.iterdir()):
                target = self.out / f.name
                os.replace(f, target)
                moved.append(target)
            for name in sorted(earlier - {f.name for f in moved}):
                (self.out / name).unlink(missing_ok=True)
        except OSError as err:
            raise RvmsimError(f"{self.out}: "
                              f"{write_problem(err, 'cannot move the results in')}") from None
        self.discard()
        return moved

    def discard(self) -> None:
        """Remove the staging folder and whatever is left in it."""
        shutil.rmtree(self.dir, ignore_errors=True)


def output_lock(out: str | Path) -> FolderLock:
    """The writer lock of a station's output folder (``eol.lock``, ``eol.pid`` in it): one
    station run at a time per folder; a second fails at once with one line."""
    return FolderLock(out, "eol", "station output folder")


def earlier_run_files(out: Path) -> set[str]:
    """The files the station run already in ``out`` wrote there: its cars' files as its
    ``eol.json`` lists them, and the result files.  Only plain names of files directly in
    ``out`` count; an unreadable or foreign ``eol.json`` names none but the result files
    (nothing else of the folder is ever removed)."""
    names = set(RESULT_FILES)
    try:
        data = read_json_file(out / "eol.json")
    except RvmsimError:  # missing, unreadable, over the limits: its files are not known
        return names
    results = data.get("results") if isinstance(data, dict) else None
    for car in results if isinstance(results, list) else []:
        files = car.get("files") if isinstance(car, dict) else None
        for name in (files.values() if isinstance(files, dict) else ()):
            if (isinstance(name, str) and name and name == Path(name).name
                    and not name.startswith(".") and (out / name).is_file()):
                names.add(name)
    return names


def _write_text(path: Path, text: str) -> None:
    try:
        write_text(path, text)  # a capture's name that is not UTF-8 written as \xff
    except OSError as err:
        raise RvmsimError(f"{path}: {write_problem(err)}") from None


def write_car(car: CarResult, folder: Path, output: OutputSpec) -> dict[str, str]:
    """Write one car's parameter file and pictures into ``folder``.

    Returns
    -------
    dict of str to str
        File name by kind: ``params``, ``guidelines`` (the car's guideline table, when it
        has one), ``rvm``, ``annotated`` (or ``landmarks``, ``overlay`` for a car whose pose
        was not recovered).
    """
    files: dict[str, str] = {}
    if car.correction is not None:
        head = (f"# rvmsim eol: the ISP parameters of the car of {car.capture}: "
                f"{car.verdict}{': ' + car.reason if car.reason else ''}")
        doc = params_to_dict(car.correction.params, output)
        files["params"] = f"{car.name}.yaml"
        _write_text(folder / files["params"], " ".join(head.split()) + "\n"
                    + yaml.safe_dump(doc, sort_keys=False))
    if car.correction is not None and car.guidelines is not None:
        files["guidelines"] = f"{car.name}{TABLE_SUFFIX}"
        try:
            (folder / files["guidelines"]).write_bytes(car.guidelines.data)
        except OSError as err:
            raise RvmsimError(f"{folder / files['guidelines']}: {write_problem(err)}") from None
    keys = ("rvm", "annotated") if car.correction is not None else _FAILURE_PICTURES
    for key in keys:
        if key in car.images:
            files[key] = f"{car.name}_{key}.png"
            write_png(folder / files[key], car.images[key])
    return files


def csv_rows(result: StationResult) -> tuple[list[str], list[dict[str, Any]]]:
    """The columns of ``eol.csv`` and one row per car: capture, verdict, reason, the
    deviation (mm, degrees), the pose fit (landmarks, RMS px), each written parameter's
    value and offset, the law's residual (px), the EC score and each EC's value and
    pass/fail, the parameter file, its guideline table and the table's SHA-256, the seconds
    spent.  Empty cells: not measured."""
    ec_ids = next((tuple(i.id for i in c.ec.items) for c in result.cars if c.ec is not None),
                  ())
    written = [n for n in result.written]
    offsets = [n for n in written if n != "v_pan"]
    columns = (["capture", "name", "verdict", "reason", *MOUNT_AXES, "landmarks", "rms_px"]
               + written + [f"offset_{n}" for n in offsets]
               + ["residual_rms_px", "ec_score"]
               + [c for i in ec_ids for c in (f"ec_{i}", f"ec_{i}_pass")]
               + ["params_file", "guidelines_file", "guidelines_sha256", "seconds"])
    rows = []
    for car in result.cars:
        row: dict[str, Any] = {"capture": car.capture, "name": car.name,
                               "verdict": car.verdict, "reason": car.reason,
                               "landmarks": car.landmarks, "rms_px": _num(car.rms_px),
                               "params_file": car.files.get("params", ""),
                               "guidelines_file": car.files.get("guidelines", ""),
                               "guidelines_sha256": "" if car.guidelines is None
                               or "guidelines" not in car.files else car.guidelines.sha256,
                               "seconds": round(car.seconds, 3)}
        if car.deviation is not None:
            row.update({n: round(v, 4) for n, v in zip(MOUNT_AXES, car.deviation.as_offsets())})
        corr = car.correction
        if corr is not None:
            row.update({n: round(corr.values[n], 6) for n in written})
            row.update({f"offset_{n}": round(corr.offsets[n], 6) for n in offsets})
            row["residual_rms_px"] = round(corr.residual_rms_px, 4)
        if car.ec is not None:
            row["ec_score"] = round(car.ec.score, 6)
            for item in car.ec.items:
                row[f"ec_{item.id}"] = _num(item.value)
                row[f"ec_{item.id}_pass"] = "" if not item.enabled else (
                    "pass" if item.passed else "FAIL")
        rows.append(row)
    return columns, rows


def _num(v: float | None) -> float | str:
    return "" if v is None else round(float(v), 6)


def write_tables(result: StationResult, folder: Path) -> list[Path]:
    """Write ``eol.json`` and ``eol.csv`` into ``folder``; returns their paths."""
    js, cs = folder / RESULT_FILES[0], folder / RESULT_FILES[1]
    _write_text(js, json.dumps(result.as_dict(), indent=2, default=json_default) + "\n")
    columns, rows = csv_rows(result)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    _write_text(cs, buf.getvalue())
    return [js, cs]
