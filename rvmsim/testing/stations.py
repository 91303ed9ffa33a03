"""The EOL station the tests use (not a test module; tools/bench_eol.py uses it too):
bundled vehicle A with a station of its own, a 6 m × 2.4 m ground mat of 0.3 m squares
behind the car with side bands along it (``eol.ground_patterns``: not at the FMVSS test site
the ECs are judged on), the platform setting tuned for vehicle A, and synthetic captures of
cars whose camera mount deviates by a known amount (the station rendered from the deviated
camera, through the render cache)."""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from rvmsim._io import write_png
from rvmsim.compensation import Deviation
from rvmsim.eol import synthetic_capture
from rvmsim.isp import IspParams, OutputSpec, load_params, params_to_dict
from rvmsim.scene import Scene, scene_from_dict

from .scenes import SCENES, small_scene_doc

HERE = Path(__file__).resolve().parent
#: Vehicle A's tuned platform setting (full sensor).
TUNED = HERE / "vehicle_a_tuned.yaml"
#: The station's camera: half of vehicle A's 1280 × 960 (its own scene, with the mat, so it
#: shares no render with the test scale's; the station's claims, 1 mm and 0.05°, need it).
HALF = 0.5
#: The station's mat (its own target, not at the test site).
STATION_MAT: dict[str, Any] = {
    "name": "station mat", "origin": [-3.0, 0.3], "square_size": 0.3,
    "checker": [[0, 0, 6, 2.4], [0, -3, 1.8, 0], [4.2, -3, 6, 0]],
}
EOL = {"target": "station mat", "ground_patterns": [STATION_MAT]}


def station_doc(scale: float = HALF, *, eol: dict[str, Any] | None = None,
                edit: dict[str, Any] | None = None) -> dict[str, Any]:
    """Vehicle A on ``scale`` of its sensor with the station (``eol``, default :data:`EOL`)."""
    return small_scene_doc("a", scale, edit={"eol": eol if eol is not None else EOL,
                                             **(edit or {})})


@functools.lru_cache(maxsize=None)
def station_scene(scale: float = HALF) -> Scene:
    return scene_from_dict(station_doc(scale), base_dir=SCENES,
                           source=f"vehicle_a_station_x{scale:g}.yaml")


def platform(scale: float = HALF) -> tuple[IspParams, OutputSpec]:
    """The tuned setting for ``scale`` of the sensor."""
    params, output = load_params(TUNED)
    return params.for_input_scale(scale), output


def write_inputs(folder: Path, scale: float = HALF, *, eol: dict[str, Any] | None = None,
                 edit: dict[str, Any] | None = None) -> tuple[Path, Path]:
    """The scene file and params file of the station, written into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    scene = folder / "station.yaml"
    scene.write_text(yaml.safe_dump(station_doc(scale, eol=eol, edit=edit), sort_keys=False))
    params, output = platform(scale)
    p = folder / "params.yaml"
    p.write_text(yaml.safe_dump(params_to_dict(params, output), sort_keys=False))
    return scene, p


@functools.lru_cache(maxsize=None)
def capture(deviation: Deviation, scale: float = HALF) -> np.ndarray:
    """The capture of a car whose camera deviates by ``deviation`` (the station, rendered)."""
    return synthetic_capture(station_scene(scale), deviation).color


def write_capture(path: Path, deviation: Deviation, scale: float = HALF) -> Path:
    write_png(path, capture(deviation, scale))
    return path
