"""End-of-line (EOL) compensation: a platform setting plus per-car values written at the end
of the line from the camera's measured mount.

Modules: :mod:`.model` (what is written, its ranges, the station's accuracy; files),
:mod:`.law` (from a measured deviation to the per-car values, exact in the ISP's geometry),
:mod:`.station` (the station's measurement error).  See docs/compensation.md.
"""

from __future__ import annotations

from .model import (CompensationModel, DEFAULT_COMPENSATION, compensation_for,
                    compensation_from_dict, compensation_from_spec, load_compensation, measured_load_index)
from .law import (Correction, CompensationLaw, Deviation, MIN_REFERENCE_POINTS, deviated_camera,
                  deviated_pose, loaded_deviation, reference_points)
from .station import edge_error, measured_deviation, station_error

__all__ = [
    "CompensationModel",
    "DEFAULT_COMPENSATION",
    "compensation_for",
    "compensation_from_dict",
    "compensation_from_spec",
    "load_compensation",
    "measured_load_index",
    "Correction",
    "CompensationLaw",
    "Deviation",
    "MIN_REFERENCE_POINTS",
    "deviated_camera",
    "deviated_pose",
    "loaded_deviation",
    "reference_points",
    "measured_deviation",
    "edge_error",
    "station_error",
]
