"""rvmsim.pose.matching: finding the landmarks in a capture."""

from __future__ import annotations

import numpy as np

from rvmsim.pose import find_landmarks
from rvmsim.pose.landmarks import visible_landmarks

from rvmsim.testing.captures import base, perturbed_validation


def test_corners_of_the_synthetic_frame_are_found_where_predicted():
    """The synthetic frame as the capture: every usable corner is found, within 0.5 px of
    its projection, and no unusable one is searched for."""
    sc, syn = base()
    lm = visible_landmarks(sc, syn, 8)
    cam = syn.camera
    found, ncc, method, pred = find_landmarks(syn.color, syn, sc, lm.corners,
                                              position=cam.position, rotation=cam.rotation,
                                              radius_px=10.0, usable=lm.usable)
    np.testing.assert_allclose(pred, lm.predicted_px)
    ok = np.isfinite(found[:, 0])
    assert not ok[~lm.usable].any() and all(method[n] == "" for n in np.flatnonzero(~lm.usable))
    assert ok[lm.usable].mean() > 0.9
    err = np.linalg.norm(found[ok] - pred[ok], axis=1)
    assert err.max() < 0.5, err.max()
    assert (ncc[ok] >= 0.6).all()


def test_board_is_found_by_the_chessboard_detector():
    res, _ = perturbed_validation()
    board = [m for m in res.landmarks if m.name.startswith("board_inner")]
    assert len(board) == 12
    assert all(m.method == "chessboard" and m.inlier for m in board)
    assert max(m.error_after_px for m in board) < 1.0
