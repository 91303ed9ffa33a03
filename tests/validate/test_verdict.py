"""rvmsim.validate.verdict: the checks against the tolerances."""

from __future__ import annotations

from rvmsim.pose import PoseCorrection
from rvmsim.validate import Check, EdgeComparison, Tolerances
from rvmsim.validate.verdict import judge

CORRECTION = PoseCorrection((3.0, 4.0, 0.0), 0.1, -0.6, 0.2, (0, 0, 0), (0, 0, 0),
                            (0.0, -1.0, 0.0), 0.0, 36.0, 0.0)
EDGES = EdgeComparison(1.5, 1.0, 2.0, 0.8, 100, 120)


def test_checks_and_their_limits():
    assert CORRECTION.d_position_norm_mm == 5.0 and CORRECTION.max_d_angle_deg == 0.6
    checks = judge(0.4, CORRECTION, EDGES, Tolerances())
    assert [(k.name, k.value, k.limit, k.passed) for k in checks] == [
        ("landmark_rms_after_correction_px", 0.4, 2.0, True),
        ("pose_position_correction_mm", 5.0, 30.0, True),
        ("pose_angle_correction_deg", 0.6, 0.5, False),
    ]
    judged = judge(0.4, CORRECTION, EDGES, Tolerances(max_chamfer_px=1.0, max_angle_deg=0.6))
    assert [k.passed for k in judged] == [True, True, True, False]
    assert judged[-1].name == "edge_chamfer_px" and "edge overlay" in judged[-1].hint


def test_a_check_passes_at_its_limit():
    assert Check("x", 1.0, 1.0, "").passed and not Check("x", 1.0 + 1e-12, 1.0, "").passed
