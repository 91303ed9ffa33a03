"""The test site's surfaces: FMVSS object dimensions, stripes and patches, ground patterns."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from rvmsim import labels as L
from rvmsim.scene import GroundPattern, build_parts, pattern_point, pattern_shade, scene_from_dict
from rvmsim.scene.fmvss111 import OBJECT_POSITIONS_M
from rvmsim.scene.site import pattern_cells

from ..conftest import bundled_scene


def _parts(letter="a"):
    return {p.name: p for p in build_parts(bundled_scene(letter))}


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


def test_pattern_shade_matches_the_pattern_meshes():
    """At every checker square's centre pattern_shade gives the colour its mesh has; white
    rectangles and discs lie over the checker, and nothing lies off the pattern."""
    pattern = GroundPattern(origin=(1.0, 2.0), yaw_deg=30.0, square_size=0.2,
                            checker=[[0.0, 0.0, 1.2, 0.8]], white=[[0.4, 0.0, 0.8, 0.4]],
                            circles=[[1.0, 0.6, 0.1]])
    data = {
        "name": "t",
        "camera": {"image_size": [64, 48], "intrinsics": {"fx": 20.0, "fy": 20.0},
                   "mount": {"position": [0.0, -1.0, -0.1]}},
        "vehicle": {"bumper": {"width": 1.8, "bottom": 0.3, "top": 0.6, "depth": 0.3}},
        "test_site": {"ground_patterns": [pattern.model_dump()]},
    }
    parts = {p.name: p for p in build_parts(scene_from_dict(data))}
    assert {"pattern0_black", "pattern0_white", "pattern0_white_rects", "pattern0_circles"} <= set(parts)
    assert all(parts[n].label == L.GROUND_PATTERN for n in parts if n.startswith("pattern0"))
    cells = pattern_cells(pattern)
    assert len(cells) == 6 * 4
    for (i, j), (u0, v0, u1, v1) in cells.items():
        u, v = (u0 + u1) / 2, (v0 + v1) / 2
        x, _, z = pattern_point(pattern, u, v)
        shade = pattern_shade(pattern, np.array([x]), np.array([z]))[0]
        in_white = 0.4 <= u < 0.8 and v < 0.4
        in_disc = math.hypot(u - 1.0, v - 0.6) < 0.05
        expected = 0.0 if in_disc else 1.0 if in_white else float((i + j) % 2)
        assert shade == expected, (i, j)
        mesh = parts["pattern0_black" if (i + j) % 2 == 0 else "pattern0_white"].mesh
        _, dist, _ = trimesh.proximity.closest_point(mesh, np.array([[x, -0.004, z]]))
        assert dist[0] < 1e-6
    off = pattern_point(pattern, -0.1, 0.3)
    assert np.isnan(pattern_shade(pattern, np.array([off[0]]), np.array([off[2]]))[0])
