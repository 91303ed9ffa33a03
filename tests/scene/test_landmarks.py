"""Landmarks: known points lie on their labelled parts; checker corners are the inner ones."""

from __future__ import annotations

import numpy as np
import trimesh

from rvmsim import labels as L
from rvmsim.scene import build_parts, checker_corners, site_landmarks

from ..conftest import SCENES, bundled_scene


def test_landmarks_lie_on_their_parts():
    parts = build_parts(bundled_scene("a"))
    meshes: dict[int, list] = {}
    for p in parts:
        meshes.setdefault(p.label, []).append(p.mesh)
    lms = site_landmarks(bundled_scene("a"))
    assert len(lms) > 30
    for lm in lms:
        mesh = trimesh.util.concatenate(meshes[lm.label])
        _, dist, _ = trimesh.proximity.closest_point(mesh, np.array([lm.point]))
        assert dist[0] < 1e-3, lm.name


def test_board_inner_corners_and_landmark_kinds():
    scene = bundled_scene("a")
    board = scene.test_site.board
    corners = [c for c in checker_corners(scene) if c.label == L.BOARD]
    assert len(corners) == (board.squares[0] - 1) * (board.squares[1] - 1)
    for c in corners:
        np.testing.assert_allclose(np.linalg.norm(c.normal), 1.0, atol=1e-12)
    lms = {lm.name: lm for lm in site_landmarks(scene)}
    assert {lm.kind for lm in lms.values()} == {"interior", "edge", "corner"}
    assert {f"board_corner_{t}" for t in ("00", "10", "11", "01")} <= set(lms)
    assert {c.name for c in corners} <= set(lms)


def test_ground_pattern_corners_skip_covered_squares():
    """The real mat's circles and white squares hide the corners they touch."""
    from rvmsim.scene import load_scene

    scene = load_scene(SCENES / "real" / "baic_eu5_rear.yaml")
    pattern = scene.test_site.ground_patterns[0]
    s = pattern.square_size
    corners = [c for c in checker_corners(scene) if c.label == L.GROUND_PATTERN]
    assert corners
    for c in corners:
        _, i, j = c.name.rsplit("_", 2)
        u, v = int(i) * s, int(j) * s
        for w0, x0, w1, x1 in pattern.white:  # no white rectangle meets the four squares
            assert not (w0 < u + s - 1e-9 and w1 > u - s + 1e-9 and x0 < v + s - 1e-9
                        and x1 > v - s + 1e-9), c.name
