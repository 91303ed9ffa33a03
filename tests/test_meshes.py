"""Meshes: FMVSS object dimensions, stripe geometry, body parts, mesh files."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from rvmsim import labels as L
from rvmsim.scene import build_parts, cylinder_side, disk, site_landmarks, swept_block
from rvmsim.scene import BlockPart, scene_from_dict

from .conftest import bundled_scene


def _parts(letter="a"):
    return {p.name: p for p in build_parts(bundled_scene(letter))}


def test_every_part_has_a_distinct_known_label():
    parts = build_parts(bundled_scene("a"))
    names = L.label_names()
    by_label: dict[int, set[str]] = {}
    for p in parts:
        assert p.label in names
        by_label.setdefault(p.label, set()).add(p.name)
    # Only the board's plate and its squares share a label.
    shared = {k: v for k, v in by_label.items() if len(v) > 1}
    assert shared == {L.BOARD: {"pattern_board", "pattern_board_squares"}}
    expected = {"ground", "bumper", "garnish", "trunk", "pattern_board"}
    expected |= {f"object_{c}" for c in "ABCDEFG"} | {f"stripe_{c}" for c in "ABCDEFG"}
    expected |= {"stripe_F_lower_patch", "stripe_G_lower_patch"}
    expected |= {"guide_side_neg_x", "guide_side_pos_x"} | {f"guide_cross_{n}" for n in (1, 2, 3, 4)}
    assert expected <= {p.name for p in parts}


@pytest.mark.parametrize("letter", list("ABCDEFG"))
def test_test_object_dimensions(letter):
    parts = _parts()
    obj = trimesh.util.concatenate(
        [p.mesh for n, p in parts.items() if n.startswith((f"object_{letter}", f"stripe_{letter}"))]
    )
    lo, hi = obj.bounds
    assert hi[1] - lo[1] == pytest.approx(0.80)  # height
    assert lo[1] == pytest.approx(-0.80) and hi[1] == pytest.approx(0.0)
    assert hi[0] - lo[0] == pytest.approx(0.30, abs=1e-4)  # diameter
    centre = ((lo[0] + hi[0]) / 2, (lo[2] + hi[2]) / 2)
    from rvmsim.scene.fmvss111 import OBJECT_POSITIONS_M

    assert centre == pytest.approx(OBJECT_POSITIONS_M[letter], abs=1e-4)


def test_horizontal_band_on_a_to_e():
    band = _parts()["stripe_B"].mesh
    lo, hi = band.bounds
    assert -lo[1] == pytest.approx(0.80) and -hi[1] == pytest.approx(0.65)
    # Area of a full band: circumference × 150 mm (polygon, 128 sides).
    assert band.area == pytest.approx(math.pi * 0.30 * 0.15, rel=1e-3)


@pytest.mark.parametrize("letter", ["F", "G"])
def test_vertical_stripe_and_lower_patch(letter):
    parts = _parts()
    stripe, patch = parts[f"stripe_{letter}"].mesh, parts[f"stripe_{letter}_lower_patch"].mesh
    # 150 mm along the circumference: area = 0.15 m × height.
    assert patch.area == pytest.approx(0.15 * 0.15, rel=2e-3)
    assert stripe.area == pytest.approx(0.15 * 0.65, rel=2e-3)
    assert -patch.bounds[0][1] == pytest.approx(0.15) and patch.bounds[1][1] == pytest.approx(0)
    # Default facing: toward the vehicle centre line (x = 0) at the object's own z.
    obj_x = -1.52 if letter == "F" else 1.52
    mid = patch.vertices.mean(axis=0)
    assert abs(mid[0]) < abs(obj_x) and mid[2] == pytest.approx(0.30, abs=1e-3)


def test_stripe_facing_options():
    data = {
        "name": "t",
        "camera": {"image_size": [64, 48], "intrinsics": {"fx": 20.0, "fy": 20.0},
                   "mount": {"position": [0.0, -1.0, -0.1]}},
        "vehicle": {"bumper": {"width": 1.8, "bottom": 0.3, "top": 0.6, "depth": 0.3}},
        "test_site": {"vertical_stripe_facing": "vehicle"},
    }
    patch = {p.name: p for p in build_parts(scene_from_dict(data))}["stripe_G_lower_patch"]
    assert patch.mesh.vertices[:, 2].mean() < 0.30  # faces −Z, toward the car
    data["test_site"]["vertical_stripe_facing"] = 0.0
    patch = {p.name: p for p in build_parts(scene_from_dict(data))}["stripe_G_lower_patch"]
    assert patch.mesh.vertices[:, 2].mean() > 0.30  # azimuth 0 faces +Z


def test_primitives_face_outward():
    tube = cylinder_side(0.15, 0.0, 0.8, 0, 360, (1.0, 2.0))
    radial = tube.triangles_center[:, [0, 2]] - [1.0, 2.0]
    assert np.all(np.einsum("ij,ij->i", tube.face_normals[:, [0, 2]], radial) > 0)
    top = disk(0.15, 0.8, (1.0, 2.0))
    assert np.all(top.face_normals[:, 1] < -0.99)  # up is −Y
    block = swept_block(BlockPart(width=1.8, bottom=0.3, top=0.6, depth=0.3, sweep=0.2, lean_deg=8))
    assert block.is_watertight and block.volume > 0
    lo, hi = block.bounds
    assert hi[2] == pytest.approx(0.0, abs=1e-3)  # rearmost point on the bumper plane
    assert -lo[1] == pytest.approx(0.6) and -hi[1] == pytest.approx(0.3)


def test_mesh_file_part_units_and_transform():
    scene = bundled_scene("f")
    bumper = _parts("f")["bumper"].mesh
    raw = trimesh.load(str(scene.resolve_path(scene.vehicle.bumper.mesh)), force="mesh")
    np.testing.assert_allclose(bumper.bounds, raw.bounds / 1000.0, atol=1e-9)  # mm → m
    assert raw.bounds[1, 0] - raw.bounds[0, 0] > 1000  # the file really is in millimetres
    assert bumper.bounds[1, 2] == pytest.approx(0.0, abs=1e-3)  # rearmost point on Z = 0
    # A transform moves it: 0.1 m rearward and turned 90° about the vertical.
    data = scene.model_dump()
    data["vehicle"]["bumper"].update(translation=(0.0, 0.0, 0.1), rotation_deg=(90.0, 0.0, 0.0))
    from rvmsim.scene import scene_from_dict

    moved = {p.name: p for p in build_parts(scene_from_dict(data, base_dir=scene.base_dir))}
    lo, hi = moved["bumper"].mesh.bounds
    assert hi[2] - lo[2] == pytest.approx(raw.bounds[1, 0] / 1000 - raw.bounds[0, 0] / 1000)


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
