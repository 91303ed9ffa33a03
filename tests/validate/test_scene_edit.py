"""rvmsim.validate.scene_edit: the scene with the corrected mount, in memory and as a file."""

from __future__ import annotations

import pytest
import yaml

from rvmsim.errors import SceneError
from rvmsim.scene import load_scene
from rvmsim.pose import PoseCorrection, scene_with_mount
from rvmsim.validate import write_corrected_scene

from rvmsim.testing.captures import base, scene_dict

CORRECTION = PoseCorrection((1.0, 2.0, 3.0), 0.1, 0.2, 0.3, (0, 0, 0), (0, 0, 0),
                            (0.021, -0.968, -0.117), 0.6, 36.2, -0.2)


def test_scene_with_mount_changes_only_the_mount():
    sc, _ = base()
    moved = scene_with_mount(sc, CORRECTION)
    m = moved.camera.mount
    assert tuple(m.position) == CORRECTION.position_m
    assert (m.yaw_deg, m.pitch_deg, m.roll_deg) == (0.6, 36.2, -0.2)
    assert moved.test_site == sc.test_site and moved.camera.intrinsics == sc.camera.intrinsics
    assert sc.camera.mount.pitch_deg == 36.0  # the original is unchanged


def test_write_corrected_scene_rewrites_block_lists_inserts_missing_angles(tmp_path):
    src = tmp_path / "s.yaml"
    d = scene_dict({"position": [0.02, -0.97, -0.12]})  # no angles: they default to 0
    src.write_text("# keep me\n" + yaml.safe_dump(d, sort_keys=False))  # block-style lists
    assert "position:\n" in src.read_text()
    out = write_corrected_scene(src, CORRECTION, tmp_path / "o.yaml")
    text = out.read_text()
    assert text.startswith("# keep me\n")
    m = load_scene(out).camera.mount
    assert (m.yaw_deg, m.pitch_deg, m.roll_deg) == (0.6, 36.2, -0.2)
    assert tuple(m.position) == (0.021, -0.968, -0.117)
    assert load_scene(out).test_site == load_scene(src).test_site
    odd = src.read_text().replace("    - 0.02\n", "    - !!float 0.02\n")
    src.write_text(odd)
    with pytest.raises(SceneError, match="camera.mount.position: cannot rewrite") as err:
        write_corrected_scene(src, CORRECTION, tmp_path / "o2.yaml")
    assert err.value.file == str(src) and err.value.line is not None
    assert not (tmp_path / "o2.yaml").exists()


def test_flow_values_keep_their_comments(tmp_path):
    src = tmp_path / "s.yaml"
    text = yaml.safe_dump(scene_dict(), sort_keys=False, default_flow_style=None)
    text = text.replace("pitch_deg: 36.0", "pitch_deg: 36.0   # measured")
    src.write_text(text)
    out = write_corrected_scene(src, CORRECTION, tmp_path / "sub" / "o.yaml")
    assert "pitch_deg: 36.200   # measured" in out.read_text()
    assert load_scene(out).camera.mount.pitch_deg == 36.2


def test_a_scene_without_a_mount_position_is_refused(tmp_path):
    src = tmp_path / "s.yaml"
    d = scene_dict()
    del d["camera"]["mount"]["position"]
    src.write_text(yaml.safe_dump(d, sort_keys=False))
    with pytest.raises(SceneError, match=r"s\.yaml: camera\.mount\.position: not found"):
        write_corrected_scene(src, CORRECTION, tmp_path / "o.yaml")
