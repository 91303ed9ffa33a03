"""What the station found for each car, and for all of them: frozen records.

Lengths in the scene are mm (deviations) or m (poses), angles degrees, image lengths px.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..compensation import Correction, Deviation
from ..criteria import EcResult
from ..guidelines.table import TABLE_VERSION
from ..percar import CarSolution
from ..scene import MOUNT_AXES
from .tables import TABLE_SUFFIX, CarTable

__all__ = ["CarResult", "StationResult", "PASS", "FAIL"]

PASS, FAIL = "PASS", "FAIL"


@dataclass(frozen=True)
class CarResult:
    """One car at the station.

    Attributes
    ----------
    capture : str
        The capture's file (or the name it was given).
    name : str
        The stem of the car's output files (``<name>.yaml``, ``<name>_rvm.png``, …).
    reasons : tuple of str
        Why the car fails (empty: it passes): ``pose not recovered …``, ``EOL range
        exceeded: …``, ``EC 2-3 fails``.
    deviation : Deviation or None
        The camera's measured deviation from the design pose (mm and degrees), as the
        station reads it in its load state (what the law corrects);
        None when the pose was not recovered.
    sigma : (6,) tuple of float or None
        One standard error of each deviation axis, from the pose fit (mm, degrees).
    landmarks : int
        Target corners the pose was fitted to (inliers).
    rms_px : float or None
        Their reprojection RMS at the measured pose, px.
    correction : Correction or None
        The per-car values (:meth:`rvmsim.compensation.CompensationLaw.correct`).
    ec : EcResult or None
        Every EC on the car's corrected RVM image.
    images : dict of str to (H, W, 3) uint8
        ``rvm`` (the capture through the car's ISP parameters), ``annotated`` (the ECs
        drawn on it); a car whose pose was not recovered: the validation's pictures
        (``landmarks``, ``overlay``, ``edges``).
    seconds : float
        Time spent on the car, s.
    files : dict of str to str
        The car's files in the output folder by kind (``params``, ``rvm``, ``annotated``,
        ``landmarks``, ``overlay``), once written.
    solution : CarSolution or None
        The law's values and the station's verdict on the car's picture (status ``pass``,
        ``marginal``, ``infeasible``; each EC's value, margin and uncertainty).
    body_edge : dict or None
        The body's outline found in the capture (:meth:`rvmsim.eol.BodyEdge.as_dict`).
    guidelines : CarTable or None
        The car's parking-guideline table (:mod:`.tables`: its measured pose and per-car
        values); None when its pose was not recovered or the scene has no running gear.
    """

    capture: str
    name: str
    reasons: tuple[str, ...]
    deviation: Deviation | None = None
    sigma: tuple[float, ...] | None = None
    landmarks: int = 0
    rms_px: float | None = None
    correction: Correction | None = None
    ec: EcResult | None = None
    images: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)
    seconds: float = 0.0
    files: dict[str, str] = field(default_factory=dict, compare=False)
    solution: CarSolution | None = field(default=None, compare=False)
    body_edge: dict[str, Any] | None = None
    guidelines: CarTable | None = field(default=None, compare=False)

    @property
    def passed(self) -> bool:
        return not self.reasons

    @property
    def verdict(self) -> str:
        return PASS if self.passed else FAIL

    @property
    def status(self) -> str:
        """``pass``, ``marginal``, ``infeasible``, ``fail`` (an EC or a range), or
        ``no pose`` (the pose was not recovered)."""
        if self.solution is None:
            return "no pose" if self.deviation is None else ("pass" if self.passed else "fail")
        return self.solution.status

    @property
    def reason(self) -> str:
        """The reasons as one line ("" when the car passes)."""
        return "; ".join(self.reasons)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (numbers mm, degrees, px; None where not measured)."""
        dev = self.deviation
        return {
            "capture": self.capture, "name": self.name, "verdict": self.verdict,
            "reasons": list(self.reasons),
            "deviation": None if dev is None else dev.as_dict(),
            "deviation_sigma": None if self.sigma is None else {
                n: round(s, 4) for n, s in zip(MOUNT_AXES, self.sigma)},
            "landmarks": self.landmarks, "rms_px": self.rms_px,
            "status": self.status,
            "correction": None if self.correction is None else self.correction.as_dict(),
            "station": None if self.solution is None else {
                k: v for k, v in self.solution.as_dict().items()
                if k in ("law", "status", "reasons", "evaluations", "station_ecs")},
            "body_edge": self.body_edge,
            "guidelines": None if self.guidelines is None else self.guidelines.as_dict(
                self.files.get("guidelines")),
            "ecs": None if self.ec is None else self.ec.as_dict(),
            "seconds": round(self.seconds, 3), "files": dict(self.files),
        }


@dataclass(frozen=True)
class StationResult:
    """Every car of one station run, with what they were judged by.

    Attributes
    ----------
    scene_name, scene_file : str
    target : str
        The station's target (``board`` or a ground pattern's name).
    load_state : dict
        The load state the cars stand at (name, height_mm, pitch_deg).
    params_file : str
        The platform setting's file.
    output : (int, int)
        The RVM image the ECs are measured on, px.
    compensation : dict
        The compensation model (:meth:`rvmsim.compensation.CompensationModel.as_dict`).
    criteria : str
        The criteria's name.
    written : tuple of str
        The ISP parameters the EOL step writes per car.
    cars : tuple of CarResult
    timings : dict
        Seconds: ``setup`` (the station's frame, the law), ``cars`` (all cars), ``total``.
    platform_isp : dict
        The platform setting's 14 values (what a sign-off checks it judged its own setting
        by; empty: not known).
    guideline_angles : tuple of float or None
        The steering-wheel angles of every car's guideline table, degrees (None: the
        scene's vehicle has no running gear, and no table is written).
    """

    scene_name: str
    scene_file: str
    target: str
    load_state: dict[str, Any]
    params_file: str
    output: tuple[int, int]
    compensation: dict[str, Any]
    criteria: str
    written: tuple[str, ...]
    cars: tuple[CarResult, ...]
    timings: dict[str, float] = field(default_factory=dict)
    platform_isp: dict[str, float] = field(default_factory=dict)
    guideline_angles: tuple[float, ...] | None = None

    @property
    def n_pass(self) -> int:
        return sum(c.passed for c in self.cars)

    @property
    def passed(self) -> bool:
        """Whether every car passes."""
        return self.n_pass == len(self.cars)

    def count(self, status: str) -> int:
        """The cars of one :attr:`CarResult.status`."""
        return sum(c.status == status for c in self.cars)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the run's inputs, the counts and one entry per car.  The station's
        σ the model assumes (what robustness draws the station's errors with, and what
        calls a car marginal here) is under ``assumed_station_sigma``, not among the
        station's results."""
        comp = dict(self.compensation)
        station = dict(comp.pop("station", {}))
        assumed = {k: station.pop(k) for k in ("angle_sigma_deg", "position_sigma_mm",
                                               "edge_sigma_px") if k in station}
        return {
            "scene": self.scene_name, "scene_file": self.scene_file, "target": self.target,
            "load_state": self.load_state, "params_file": self.params_file,
            "platform_isp": dict(self.platform_isp), "output": list(self.output),
            "compensation": {**comp, "station": station},
            "assumed_station_sigma": {**assumed, "note": "an assumption of the compensation "
                                      "model (not measured by this run): the ECs' "
                                      "uncertainty a car is called marginal by"},
            "criteria": self.criteria, "written_params": list(self.written),
            "cars": len(self.cars), "passed": self.n_pass,
            "failed": len(self.cars) - self.n_pass, "all_pass": self.passed,
            "by_status": {st: self.count(st) for st in ("pass", "marginal", "infeasible",
                                                        "fail", "no pose")},
            "timings": {k: round(v, 3) for k, v in self.timings.items()},
            "guidelines": None if self.guideline_angles is None else {
                "format": f"RVMG {TABLE_VERSION}", "file": f"<name>{TABLE_SUFFIX}",
                "steering_deg": list(self.guideline_angles),
                "drawn_from": "each car's measured pose and per-car ISP values"},
            "results": [c.as_dict() for c in self.cars],
        }

    def summary(self) -> str:
        """A fixed-width table for the terminal, one line per car, and the count."""
        lines = [f"{'car':<28} {'verdict':<7} {'Δx,y,z mm':>20} {'Δyaw,pitch,roll °':>21}  "
                 "reason"]
        for c in self.cars:
            d = c.deviation
            pos = "-" if d is None else f"{d.x_mm:+.1f},{d.y_mm:+.1f},{d.z_mm:+.1f}"
            ang = "-" if d is None else f"{d.yaw_deg:+.2f},{d.pitch_deg:+.2f},{d.roll_deg:+.2f}"
            lines.append(f"{c.name[-28:]:<28} {c.verdict:<7} {pos:>20} {ang:>21}  {c.reason}")
        lines.append(f"{self.n_pass} of {len(self.cars)} cars pass")
        return "\n".join(lines)
