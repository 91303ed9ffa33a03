"""The end-of-line (EOL) station: each car's camera pose from a capture of the station's
target, its per-car ISP values, and every EC on its corrected picture (``rvmsim eol``).

Modules: :mod:`.geometry` (load states, the deviation of a measured pose from the nominal
mount), :mod:`.frames` (frames of a scene from any pose), :mod:`.station` (:class:`Station`:
one car's step), :mod:`.records` (:class:`CarResult`, :class:`StationResult`),
:mod:`.body` (the body's outline found in the capture, the body region re-drawn from it),
:mod:`.outputs` (the per-car parameter files, eol.json, eol.csv, pictures), :mod:`.tables`
(each car's parking-guideline table), :mod:`.run`
(:func:`run_station`: capture files in, an output folder out), :mod:`.synthetic` (captures
of the scene rendered at a deviated pose).  See docs/eol.md.
"""

from __future__ import annotations

from .body import BodyEdge, capture_labels, find_body_edge
from .geometry import car_camera, deviation_of, moved_camera, station_load
from .records import CarResult, StationResult
from .station import Station, StationSettings
from .run import car_names, run_station
from .outputs import RESULT_FILES, Staging, csv_rows, write_car, write_tables
from .tables import TABLE_SUFFIX, CarTable, car_table, guideline_angles
from .synthetic import synthetic_capture

__all__ = [
    "BodyEdge",
    "capture_labels",
    "find_body_edge",
    "car_camera",
    "deviation_of",
    "moved_camera",
    "station_load",
    "CarResult",
    "StationResult",
    "Station",
    "StationSettings",
    "synthetic_capture",
    "run_station",
    "car_names",
    "RESULT_FILES",
    "Staging",
    "csv_rows",
    "write_car",
    "write_tables",
    "TABLE_SUFFIX",
    "CarTable",
    "car_table",
    "guideline_angles",
]
