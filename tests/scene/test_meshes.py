"""build_parts: every labelled surface, body parts from blocks and mesh files."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rvmsim import labels as L
from rvmsim.scene import build_parts, scene_from_dict

from ..conftest import bundled_scene


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
    moved = {p.name: p for p in build_parts(scene_from_dict(data, base_dir=scene.base_dir))}
    lo, hi = moved["bumper"].mesh.bounds
    assert hi[2] - lo[2] == pytest.approx(raw.bounds[1, 0] / 1000 - raw.bounds[0, 0] / 1000)


def test_site_first_then_the_vehicle():
    """The renderer adds parts in this order: the test site, then the body parts."""
    names = [p.name for p in build_parts(bundled_scene("a"))]
    assert names[0] == "ground"
    body = [names.index(n) for n in ("bumper", "garnish", "trunk")]
    assert body == sorted(body) and min(body) > max(i for i, n in enumerate(names)
                                                    if n.startswith(("object_", "guide_", "pattern")))


def _scene_with_mesh(tmp_path, name: str, data: bytes, **part):
    (tmp_path / name).write_bytes(data)
    doc = bundled_scene("a").model_dump()
    doc["vehicle"]["bumper"] = {"mesh": name, **part}
    return scene_from_dict(doc, base_dir=tmp_path, source="s.yaml")


@pytest.mark.parametrize("data, words", [
    (b"", "is empty"),
    (b"v 1e30 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "coordinates up to"),
    (b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"),
    (b"v 0 0 0\nv 1 0 0\n", "no triangles"),
])
def test_unusable_mesh_files_are_one_line_errors(tmp_path, data, words):
    from rvmsim.errors import SceneError

    scene = _scene_with_mesh(tmp_path, "b.obj", data)
    with pytest.raises(SceneError, match=words) as err:
        build_parts(scene)
    assert err.value.key == "vehicle.bumper.mesh" and "b.obj" in str(err.value)


def test_mesh_vertex_limit_is_raisable(tmp_path, monkeypatch):
    from rvmsim.errors import SceneError

    box = trimesh.creation.box((0.4, 0.2, 0.1))
    scene = _scene_with_mesh(tmp_path, "b.obj", box.export(file_type="obj").encode())
    monkeypatch.setenv("RVMSIM_MAX_MESH_VERTICES", "4")
    with pytest.raises(SceneError, match="over the limit of 4"):
        build_parts(scene)
    monkeypatch.setenv("RVMSIM_MAX_MESH_VERTICES", "1000")
    bumper = {p.name: p for p in build_parts(scene)}["bumper"].mesh
    assert len(bumper.vertices) == len(box.vertices)


def test_a_mesh_in_mm_far_from_the_origin_suggests_the_units(tmp_path):
    from rvmsim.errors import SceneError

    far = b"v 2e6 0 0\nv 2e6 100 0\nv 2e6 0 100\nf 1 2 3\n"
    with pytest.raises(SceneError, match="units: mm.*are its units right"):
        build_parts(_scene_with_mesh(tmp_path, "b.obj", far, units="mm"))
    near = _scene_with_mesh(tmp_path, "c.obj", far.replace(b"2e6", b"2e5"), units="mm")
    assert {p.name for p in build_parts(near)} >= {"bumper"}
