"""rvmsim.pose.find: the mount pose in a capture, without a validation's edges, RVM images
or verdict (what ``rvmsim eol`` uses for a car's pose)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import rvmsim
from rvmsim.pose import PoseFailure, PoseSettings, find_mount
from rvmsim.testing.captures import D_POS_MM, D_YPR_DEG, MOUNT, base, perturbed
from rvmsim.validate import ValidationSettings, validate


def test_find_mount_recovers_the_perturbed_pose():
    """The capture was rendered 6/−4/8 mm and 0.8/−0.7/0.5° off the scene's mount: the fit
    gives back those changes, and it reprojects the found corners within 1 px RMS."""
    sc, syn = base()
    truth, cap = perturbed()
    fit = find_mount(sc, cap, syn, PoseSettings())
    c = fit.correction
    assert np.allclose(c.d_position_mm, D_POS_MM, atol=3.0), c.d_position_mm
    assert np.allclose((c.d_yaw_deg, c.d_pitch_deg, c.d_roll_deg), D_YPR_DEG, atol=0.1)
    assert np.allclose(c.position_m, np.add(MOUNT["position"], np.array(D_POS_MM) / 1000),
                       atol=3e-3)
    # the corrected pose is the true camera's, checked by projecting with it independently
    assert np.allclose(fit.position_m, truth.camera.position, atol=3e-3)
    assert np.degrees(np.arccos(np.clip((np.trace(fit.rotation.T @ truth.camera.rotation) - 1)
                                        / 2, -1, 1))) < 0.1
    assert fit.n_inliers >= 20 and fit.rms_after_px < 1.0


def test_validate_reports_the_pose_find_mount_gives():
    """validate's pose is find_mount's: one search, not two."""
    sc, syn = base()
    _, cap = perturbed()
    fit = find_mount(sc, cap, syn, ValidationSettings().pose)
    res = validate(sc, cap, ValidationSettings(rerender=False), synthetic=syn)
    assert res.correction == fit.correction
    assert res.landmarks == fit.landmarks and res.start == fit.start


def test_a_failure_carries_the_predicted_landmarks():
    """A capture that shows nothing of the scene: a detection failure, with every usable
    landmark predicted and none found (what the pictures of a failed car draw)."""
    sc, syn = base()
    blank = np.full_like(syn.color, 128)
    with pytest.raises(PoseFailure) as err:
        find_mount(sc, blank, syn, PoseSettings(global_start=False, dense_align=False))
    assert err.value.step == "detection"
    assert len(err.value.landmarks) >= 8
    assert all(m.found_px is None and not m.inlier for m in err.value.landmarks)


def test_eol_does_not_run_a_validation():
    """The station finds a car's pose with rvmsim.pose: no module of rvmsim.eol imports
    rvmsim.validate."""
    root = Path(rvmsim.__file__).parent / "eol"
    for path in root.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                assert "validate" not in (node.module or "").split("."), path
