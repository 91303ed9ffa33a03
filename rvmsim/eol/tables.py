"""Each car's parking-guideline table at the end of the line: the ``RVMG`` table
(:mod:`rvmsim.guidelines.table`) drawn through the camera at the pose the station measured
and the car's per-car ISP values, for every steering angle of the car's range
(:func:`rvmsim.guidelines.steering_angles`: 10° steps and the ends).

Written as ``<name>.guidelines.bin`` beside the car's parameter file; its SHA-256 is in
eol.json.  A scene whose vehicle lacks a running-gear key gets none (eol.json says null).
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass, field
from typing import Any

from ..camera import FisheyeCamera
from ..guidelines import (compute_guidelines, guideline_view, has_running_gear, running_gear,
                          steering_angles)
from ..guidelines.table import TABLE_VERSION, table_bytes
from ..isp import IspParams, OutputSpec
from ..scene import Scene

__all__ = ["TABLE_SUFFIX", "CarTable", "guideline_angles", "car_table"]

#: A car's table file is ``<name>`` + this.
TABLE_SUFFIX = ".guidelines.bin"


@dataclass(frozen=True)
class CarTable:
    """One car's guideline table.

    Attributes
    ----------
    data : bytes
        The ``RVMG`` table (empty once written: :meth:`written`).
    sha256 : str
        Its SHA-256, hex.
    size : int
        Its length, bytes.
    """

    data: bytes = field(repr=False)
    sha256: str
    size: int

    def written(self) -> CarTable:
        """The record without the table's bytes (kept in its file)."""
        return dataclasses.replace(self, data=b"")

    def as_dict(self, file: str | None) -> dict[str, Any]:
        """JSON-ready: the file's name (None: not written), format, SHA-256 and size."""
        return {"file": file, "format": f"RVMG {TABLE_VERSION}", "sha256": self.sha256,
                "bytes": self.size}


def guideline_angles(scene: Scene) -> tuple[float, ...] | None:
    """The steering-wheel angles (degrees) of every car's table: the car's whole range in
    10° steps with its ends; None when the scene's vehicle lacks a running-gear key."""
    if not has_running_gear(scene):
        return None
    return steering_angles(running_gear(scene))


def car_table(scene: Scene, camera: FisheyeCamera, params: IspParams, output: OutputSpec,
              angles: tuple[float, ...]) -> CarTable:
    """A car's table: the scene's guidelines through ``camera`` (its measured pose, the
    scene frame) and ``params`` (its whole per-car setting) on the RVM image of record
    (``output``'s mirroring), at ``angles`` (steering-wheel degrees)."""
    view = guideline_view(scene, params, output, camera=camera)
    data = table_bytes(compute_guidelines(scene, view, angles))
    return CarTable(data, hashlib.sha256(data).hexdigest(), len(data))
