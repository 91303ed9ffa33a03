"""How far the parking guidelines land from where they claim, over a fleet after end-of-line
compensation (``rvmsim robustness --compensation``).

Each car's table is drawn as ``rvmsim eol`` draws it: through the camera at the pose the
station measured (its reading in the station's load state, with the station's error) and the
car's per-car ISP values.  It is looked at through the car's true camera with the same values
(:mod:`rvmsim.guidelines.error`: display error in px, ground error in cm, per line its
largest over its points):

- **at the station**: the car's true pose in the station's load state (the station's
  error alone);
- **in the field**: the car's true pose in its own load state (what its driver sees; a load
  state the station did not stand the car in moves the lines too).

For comparison, the platform table (the camera at its design pose, the platform setting; no
end-of-line step) looked at through each car's true camera with the platform setting.

Lines: each distance mark, the width lines, and the trajectory lines at 0 %, ±50 % and ±100 %
of the steering range (both signs one group).  Over the fleet, per line: the median, the
99th percentile and the largest of the cars' errors, and the car with the largest.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..camera import FisheyeCamera
from ..compensation import Deviation, deviated_camera, loaded_deviation
from ..guidelines import (DisplayLine, GuidelineSet, compute_guidelines, guideline_view,
                          has_running_gear, running_gear)
from ..guidelines.error import line_errors, line_group
from ..isp import IspParams, OutputSpec
from ..scene import Scene
from .compensated import true_deviation
from .samples import MountSample
from .variation import LoadState

__all__ = ["STEERING_SHARES", "GuidelineErrors", "FleetGuidelines", "fleet_guideline_errors"]

#: The steering angles the errors are given at: shares of the steering range (both signs).
STEERING_SHARES = (0.0, 0.5, 1.0)


@dataclass(frozen=True, eq=False)
class GuidelineErrors:
    """Per car and line group, the line's largest errors.

    Attributes
    ----------
    groups : tuple of str
        Line groups (``mark_1m``, ``width``, ``trajectory_0pct``, …).
    px : (n, G) float64
        Display error, px (NaN: the line not shown, or no point counted).
    cm : (n, G) float64
        Ground error, cm (NaN likewise).
    """

    groups: tuple[str, ...]
    px: np.ndarray
    cm: np.ndarray

    def of(self, group: str, unit: str = "cm") -> np.ndarray:
        """(n,) the cars' errors of one group in ``unit`` (``px`` or ``cm``)."""
        return (self.cm if unit == "cm" else self.px)[:, self.groups.index(group)]

    def distribution(self) -> dict[str, Any]:
        """JSON-ready, per group: ``px`` and ``cm`` each ``median``, ``p99``, ``max`` over the
        cars counted (None: none), ``worst_sample`` (the car with the largest ground error,
        its index in the sample set; None: none) and ``cars`` (those counted)."""
        out: dict[str, Any] = {}
        for j, g in enumerate(self.groups):
            doc: dict[str, Any] = {}
            for unit, values in (("px", self.px[:, j]), ("cm", self.cm[:, j])):
                v = values[np.isfinite(values)]
                doc[unit] = {"median": _stat(np.median, v), "p99": _stat(_p99, v),
                             "max": _stat(np.max, v)}
            cm = self.cm[:, j]
            ok = np.isfinite(cm)
            doc["worst_sample"] = int(np.argmax(np.where(ok, cm, -np.inf))) if ok.any() \
                else None
            doc["cars"] = int(ok.sum())
            out[g] = doc
        return out


def _cm(v: float | None) -> str:
    return "—" if v is None else f"{v:.1f}"


def _p99(v: np.ndarray) -> float:
    return float(np.percentile(v, 99))


def _stat(f: Any, v: np.ndarray) -> float | None:
    return round(float(f(v)), 4) if v.size else None


@dataclass(frozen=True, eq=False)
class FleetGuidelines:
    """The guidelines' errors over a fleet (the module docstring).

    Attributes
    ----------
    steering_deg : dict of str to tuple of float
        Per trajectory group, its steering-wheel angles, degrees.
    eol_station, eol_field : GuidelineErrors
        Each car's own table (measured pose, per-car values): at the station, in the field.
    platform_station, platform_field : GuidelineErrors
        The platform table (design pose, platform setting) on each car.
    """

    steering_deg: dict[str, tuple[float, ...]]
    eol_station: GuidelineErrors
    eol_field: GuidelineErrors
    platform_station: GuidelineErrors
    platform_field: GuidelineErrors

    def summary_line(self) -> str:
        """One terminal line: each distance mark's ground error after the EOL step, in the
        field, p99 and worst over the cars (cm)."""
        d = self.eol_field.distribution()
        marks = [g for g in self.eol_field.groups if g.startswith("mark_")]
        parts = [f"{g} {_cm(d[g]['cm']['p99'])}/{_cm(d[g]['cm']['max'])}" for g in marks]
        return ("guidelines after EOL, ground error in the field (p99/worst cm): "
                + (", ".join(parts) if parts else "no distance marks"))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (robustness.json's ``compensation.guidelines``)."""
        return {"definition": "per car, a line's largest error over its points: display "
                              "px |true view(G) − drawn px|, ground cm |ground under the "
                              "drawn px (true view) − G|; over the cars: median, p99, max",
                "groups": list(self.eol_field.groups),
                "steering_deg": {k: list(v) for k, v in self.steering_deg.items()},
                "eol_table": {"at_station": self.eol_station.distribution(),
                              "in_field": self.eol_field.distribution()},
                "platform_table": {"at_station": self.platform_station.distribution(),
                                   "in_field": self.platform_field.distribution()}}


def _groups(gset: GuidelineSet, shares: dict[float, str]) -> list[str]:
    names = [line_group(l) for l in gset.static]
    return list(dict.fromkeys(names)) + list(dict.fromkeys(shares.values()))


def _camera_at(scene: Scene, deviation: Deviation, load: LoadState) -> FisheyeCamera:
    """The camera of a car whose mount deviates by ``deviation`` standing in ``load``
    (scene frame, full sensor)."""
    return deviated_camera(scene, loaded_deviation(scene, deviation, load.height_mm,
                                                   load.pitch_deg))


def fleet_guideline_errors(scene: Scene, samples: Sequence[MountSample],
                           measured: Sequence[Deviation], params: Sequence[IspParams],
                           platform: IspParams, output: OutputSpec,
                           station_load: LoadState) -> FleetGuidelines | None:
    """The guidelines' errors over ``samples`` (the module docstring).

    Parameters
    ----------
    scene : Scene
        The car as designed (full sensor), with its running gear.
    samples : sequence of MountSample
        The cars (their true deviations, :func:`~rvmsim.robust.true_deviation`, and load
        states).
    measured : sequence of Deviation
        What the station read for each car in ``station_load`` (mm, degrees;
        :func:`~rvmsim.robust.station_readings`).
    params : sequence of IspParams
        Each car's per-car setting (full sensor).
    platform : IspParams
        The platform setting (full sensor).
    output : OutputSpec
        Its mirroring; the lines are drawn on the RVM image of record.
    station_load : LoadState
        The load state the station stands the cars in.

    Returns
    -------
    FleetGuidelines or None
        None when the scene's vehicle lacks a running-gear key.
    """
    if not has_running_gear(scene):
        return None
    gear = running_gear(scene)
    r = gear.steering_range_deg
    shares = {float(round(s * r * sign, 9)) + 0.0: f"trajectory_{100 * s:g}pct"
              for s in STEERING_SHARES for sign in (-1.0, 1.0)}
    angles = tuple(shares)

    def group(line: DisplayLine) -> str:
        if line.kind == "trajectory":
            assert line.steering_deg is not None
            return shares[line.steering_deg]
        return line_group(line)

    nominal = compute_guidelines(scene, guideline_view(scene, platform, output), angles)
    groups = _groups(nominal, shares)
    n, k = len(samples), len(groups)
    # (table, where, unit) → (n, k): table "eol" or "platform", where "s" or "f"
    arrays = {(t, w, u): np.full((n, k), np.nan) for t in ("eol", "platform")
              for w in ("s", "f") for u in ("px", "cm")}

    def put(table: str, where: str, i: int, errors: dict[str, tuple[float, float]]) -> None:
        for g, (px, cm) in errors.items():
            j = groups.index(g)
            arrays[table, where, "px"][i, j] = px
            arrays[table, where, "cm"][i, j] = cm

    for i, (s, m, p) in enumerate(zip(samples, measured, params)):
        truth = true_deviation(s)
        at_station = _camera_at(scene, truth, station_load)
        in_field = at_station if s.load == station_load else _camera_at(scene, truth, s.load)
        table = compute_guidelines(scene, guideline_view(scene, p, output,
                                                         camera=deviated_camera(scene, m)),
                                   angles)
        for where, cam in (("s", at_station), ("f", in_field)):
            put("eol", where, i, line_errors(
                table, guideline_view(scene, p, output, camera=cam), group=group))
            put("platform", where, i, line_errors(
                nominal, guideline_view(scene, platform, output, camera=cam), group=group))
    steering = {name: tuple(a for a, g in shares.items() if g == name)
                for name in dict.fromkeys(shares.values())}
    tup = tuple(groups)
    return FleetGuidelines(steering, *(GuidelineErrors(tup, arrays[t, w, "px"],
                                                       arrays[t, w, "cm"])
                                       for t in ("eol", "platform") for w in ("s", "f")))
