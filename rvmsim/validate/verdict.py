"""What a validation measured and what it concludes: the result records and the verdict.

Every record is a frozen dataclass.  Lengths in the image are px, lengths in the scene mm
(corrections) or m (poses), angles degrees.

Convention
----------
Pixel coordinates are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`.  Positions are in the scene frame (x driver side, y down, z rearward).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..pose import LandmarkMatch, PoseCorrection

if TYPE_CHECKING:
    from ..criteria import EcResult

__all__ = [
    "Tolerances",
    "EdgeComparison",
    "RvmComparison",
    "Check",
    "Validation",
    "judge",
]


@dataclass(frozen=True)
class Tolerances:
    """What a scene must meet to pass validation.

    Attributes
    ----------
    max_rms_px : float
        Landmark RMS error after the pose correction, px: intrinsics, lens and layout must
        explain the capture this well.
    max_position_mm : float
        Length of the mount position correction, mm.
    max_angle_deg : float
        Largest of |Δyaw|, |Δpitch|, |Δroll|, degrees.
    max_chamfer_px : float or None
        Symmetric edge chamfer of the scene as given, px; None: reported, not judged.
    min_landmarks : int
        Fewer matched landmarks than this is an error, not a verdict.
    """

    max_rms_px: float = 2.0
    max_position_mm: float = 30.0
    max_angle_deg: float = 0.5
    max_chamfer_px: float | None = None
    min_landmarks: int = 8


@dataclass(frozen=True)
class EdgeComparison:
    """Canny edges of two images compared over a mask (distances in px).

    Attributes
    ----------
    chamfer_px : float
        Mean of ``a_to_b_px`` and ``b_to_a_px``.
    a_to_b_px, b_to_a_px : float
        Mean (truncated) distance from an edge pixel of the first image to the nearest edge
        of the second, and back.
    matched_fraction : float
        Share of the edge pixels (both ways) within 2 px of the other image's edges.
    edges_a, edges_b : int
        Edge pixels of each image inside the mask.
    """

    chamfer_px: float
    a_to_b_px: float
    b_to_a_px: float
    matched_fraction: float
    edges_a: int
    edges_b: int


@dataclass(frozen=True)
class RvmComparison:
    """The capture and the synthetic frame through the ISP (``--params``).

    Attributes
    ----------
    edges : EdgeComparison
        Capture's RVM image against the synthetic RVM image.
    ec_scene : EcResult
        ECs of the scene's labels.
    ec_capture : EcResult
        ECs of the pose-corrected scene's labels (a capture has no labels of its own).
    """

    edges: EdgeComparison
    ec_scene: EcResult
    ec_capture: EcResult


@dataclass(frozen=True)
class Check:
    """One verdict check: ``value`` against ``limit`` (pass when value ≤ limit)."""

    name: str
    value: float
    limit: float
    hint: str

    @property
    def passed(self) -> bool:
        return bool(self.value <= self.limit)


def judge(rms_after_px: float, correction: PoseCorrection, edges_before: EdgeComparison,
          tolerances: Tolerances) -> tuple[Check, ...]:
    """The verdict's checks, each with what to fix when it fails.

    Parameters
    ----------
    rms_after_px : float
        Landmark RMS error after the pose correction, px.
    correction : PoseCorrection
    edges_before : EdgeComparison
        Edges with the scene's pose (judged only with ``tolerances.max_chamfer_px``).
    tolerances : Tolerances
    """
    checks = [
        Check("landmark_rms_after_correction_px", rms_after_px, tolerances.max_rms_px,
              "the corrected pose still leaves the landmarks off: check the intrinsics, the "
              "lens (k1..k4, fov) and the pattern layout against the capture"),
        Check("pose_position_correction_mm", correction.d_position_norm_mm,
              tolerances.max_position_mm,
              "the camera's mount position is off: write the corrected scene (--write-scene)"),
        Check("pose_angle_correction_deg", correction.max_d_angle_deg, tolerances.max_angle_deg,
              "the camera's mount angles are off: write the corrected scene (--write-scene)"),
    ]
    if tolerances.max_chamfer_px is not None:
        checks.append(Check("edge_chamfer_px", edges_before.chamfer_px, tolerances.max_chamfer_px,
                            "edges differ: compare the edge overlay for parts the scene "
                            "lacks or misplaces"))
    return tuple(checks)


@dataclass(frozen=True)
class Validation:
    """Everything :func:`rvmsim.validate.validate` measured.

    ``images`` holds the pictures for people (RGB uint8 arrays keyed by file stem, in the
    order they are written); it is not part of :meth:`to_dict` nor of equality.  ``start``
    says where the pose search started (the scene's pose, or the board the chessboard
    detector found).
    """

    scene_name: str
    capture: str
    image_size: tuple[int, int]
    landmarks: tuple[LandmarkMatch, ...]
    n_predicted: int
    rms_before_px: float
    max_before_px: float
    rms_after_px: float
    max_after_px: float
    correction: PoseCorrection
    edges_before: EdgeComparison
    edges_after: EdgeComparison | None
    rvm: RvmComparison | None
    checks: tuple[Check, ...]
    images: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)
    start: str = "the scene's pose"

    @property
    def n_found(self) -> int:
        return sum(m.found_px is not None for m in self.landmarks)

    @property
    def n_inliers(self) -> int:
        return sum(m.inlier for m in self.landmarks)

    @property
    def passed(self) -> bool:
        return all(c.passed for c in self.checks)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (numbers in px, mm, degrees)."""
        d: dict[str, Any] = {
            "scene": self.scene_name,
            "capture": self.capture,
            "image_size": list(self.image_size),
            "passed": self.passed,
            "start": self.start,
            "checks": [{**asdict(c), "passed": c.passed} for c in self.checks],
            "landmarks": {
                "predicted": self.n_predicted,
                "found": self.n_found,
                "inliers": self.n_inliers,
                "rms_before_px": self.rms_before_px,
                "max_before_px": self.max_before_px,
                "rms_after_px": self.rms_after_px,
                "max_after_px": self.max_after_px,
                "matches": [
                    {**asdict(m), "error_before_px": m.error_before_px,
                     "error_after_px": m.error_after_px}
                    for m in self.landmarks
                ],
            },
            "pose_correction": asdict(self.correction),
            "edges_before": asdict(self.edges_before),
            "edges_after": None if self.edges_after is None else asdict(self.edges_after),
        }
        if self.rvm is not None:
            d["rvm"] = _rvm_dict(self.rvm)
        return d

    def summary(self) -> str:
        """A few lines for the terminal."""
        c = self.correction
        lines = [
            f"start: {self.start}",
            f"landmarks: {self.n_inliers} inliers of {self.n_found} found "
            f"({self.n_predicted} predicted visible)",
            f"landmark error: RMS {self.rms_before_px:.2f} px (max {self.max_before_px:.2f}) "
            f"with the scene's pose, RMS {self.rms_after_px:.2f} px "
            f"(max {self.max_after_px:.2f}) after the pose correction",
            "pose correction: Δposition ({:+.1f}, {:+.1f}, {:+.1f}) mm ± ({:.1f}, {:.1f}, {:.1f}); "
            "Δyaw {:+.3f}° Δpitch {:+.3f}° Δroll {:+.3f}° ± ({:.3f}, {:.3f}, {:.3f})°".format(
                *c.d_position_mm, *c.sigma_position_mm, c.d_yaw_deg, c.d_pitch_deg,
                c.d_roll_deg, *c.sigma_angles_deg),
            "corrected mount: position [{:.4f}, {:.4f}, {:.4f}] m, yaw {:.3f}°, pitch {:.3f}°, "
            "roll {:.3f}°".format(*c.position_m, c.yaw_deg, c.pitch_deg, c.roll_deg),
            f"edges: chamfer {self.edges_before.chamfer_px:.2f} px with the scene's pose"
            + ("" if self.edges_after is None else
               f", {self.edges_after.chamfer_px:.2f} px after the pose correction"),
        ]
        if self.rvm is not None:
            lines += _rvm_summary(self.rvm)
        for chk in self.checks:
            mark = "ok  " if chk.passed else "FAIL"
            lines.append(f"{mark} {chk.name}: {chk.value:.3g} (limit {chk.limit:g})"
                         + ("" if chk.passed else f" — {chk.hint}"))
        failed = [c.name for c in self.checks if not c.passed]
        lines.append("verdict: PASS" if not failed else
                     "verdict: FAIL (step failed: check: " + ", ".join(failed) + ")")
        return "\n".join(lines)


def _rvm_dict(rvm: RvmComparison) -> dict[str, Any]:
    """The ``rvm`` part of :meth:`Validation.to_dict`."""
    return {
        "edges": asdict(rvm.edges),
        "ec_score_scene": rvm.ec_scene.score,
        "ec_score_capture": rvm.ec_capture.score,
        "ecs": {
            i.id: {"scene": i.as_dict(), "capture": rvm.ec_capture[i.id].as_dict()}
            for i in rvm.ec_scene.items
        },
    }


def _rvm_summary(rvm: RvmComparison) -> list[str]:
    """The RVM lines of :meth:`Validation.summary`."""
    lines = [f"RVM image: edge chamfer {rvm.edges.chamfer_px:.2f} px; EC score "
             f"{rvm.ec_scene.score:.4g} (scene) vs {rvm.ec_capture.score:.4g} "
             "(pose that explains the capture)"]
    changed = [i.id for i in rvm.ec_scene.items
               if i.enabled and i.passed != rvm.ec_capture[i.id].passed]
    if changed:
        lines.append("ECs whose pass/fail differs: " + ", ".join(changed))
    return lines
