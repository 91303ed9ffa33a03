"""rvmsim.robust.variation: variation files and scene sections."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvmsim.errors import SceneError, VariationError
from rvmsim.robust import load_variation, variation_from_scene
from rvmsim.scene import load_scene

from rvmsim.testing.scenes import load_small_scene
from .conftest import ROOT

GOOD = """\
mount:
  x_mm: {uniform: {half_width: 5}}
  pitch_deg: {normal: {sigma: 0.4, truncate: 2.5}}
  position_levels: 3
load_states:
  - {name: curb, weight: 1}
  - {name: full, height_mm: -50, pitch_deg: 1.0, weight: 3}
"""


def test_a_variation_file(tmp_path: Path):
    f = tmp_path / "var.yaml"
    f.write_text(GOOD)
    v = load_variation(f)
    assert v.axis("x_mm").kind == "uniform" and v.axis("x_mm").bound == 5.0
    assert v.axis("pitch_deg").bound == pytest.approx(1.0)
    assert not v.axis("yaw_deg").varies and v.position_levels == 3
    assert [s.probability for s in v.load_states] == [0.25, 0.75]
    assert v.load_states[1].height_mm == -50.0 and v.source == str(f)


@pytest.mark.parametrize("letter", "abcdef")
def test_the_bundled_scenes_have_realistic_variation(letter):
    v = variation_from_scene(load_scene(ROOT / "scenes" / f"vehicle_{letter}.yaml"))
    assert [v.axis(a).bound for a in ("yaw_deg", "pitch_deg", "roll_deg")] == [1.0] * 3
    assert all(v.axis(a).bound == 5.0 for a in ("x_mm", "y_mm", "z_mm"))
    full = v.load_states[-1]
    assert -80 <= full.height_mm <= -30 and 0.5 <= full.pitch_deg <= 1.5
    assert sum(s.probability for s in v.load_states) == pytest.approx(1.0)


def test_a_scene_without_a_section_varies_nothing():
    v = variation_from_scene(load_small_scene("a", variation=None))
    assert not any(a.varies for a in v.axes) and [s.name for s in v.load_states] == ["nominal"]


@pytest.mark.parametrize("text,key,words", [
    ("mount: {yaw: {uniform: {half_width: 1}}}", "mount.yaw", "unknown key"),
    ("mount: {yaw_deg: {uniform: {half_width: 1}, normal: {sigma: 1}}}", "mount.yaw_deg",
     "exactly one"),
    ("mount: {x_mm: {uniform: {half_width: -1}}}", "mount.x_mm.uniform.half_width",
     "greater than or equal"),
    ("mount: {roll_deg: {normal: {sigma: 30}}}", "mount.roll_deg", "more than"),
    ("load_states: [{name: a}, {name: a}]", "load_states", "must differ"),
    ("load_states: [{name: a, weight: 0}]", "load_states.0.weight", "greater than"),
    ("- 1\n- 2\n", "", "must be a YAML mapping"),
])
def test_bad_variation_files_name_file_and_key(tmp_path: Path, text, key, words):
    f = tmp_path / "var.yaml"
    f.write_text(text)
    with pytest.raises(VariationError) as err:
        load_variation(f)
    assert err.value.key == key and words in err.value.message and err.value.file == str(f)
    assert "\n" not in str(err.value)


def test_a_bad_scene_section_is_a_scene_error(tmp_path: Path):
    text = (ROOT / "scenes" / "vehicle_a.yaml").read_text().replace(
        "half_width: 1.0", "half_width: -1.0", 1)
    f = tmp_path / "scene.yaml"
    f.write_text(text)
    (tmp_path / "meshes").mkdir()
    with pytest.raises(SceneError, match=r"variation\.mount\.yaw_deg\.uniform\.half_width"):
        load_scene(f)


def test_a_missing_variation_file():
    with pytest.raises(VariationError, match="variation file not found"):
        load_variation("/nonexistent/var.yaml")


def test_variation_for_takes_the_file_else_the_scene_section(tmp_path: Path):
    """``--variation FILE`` wins over the scene's section; without one the section is used;
    without either, one line naming the scene and its ``variation`` key."""
    from rvmsim.robust import variation_for

    f = tmp_path / "var.yaml"
    f.write_text(GOOD)
    with_section = load_small_scene(
        "a", 0.25, variation={"mount": {"yaw_deg": {"uniform": {"half_width": 2}}}})
    assert variation_for(with_section, f) == load_variation(f)
    assert variation_for(with_section, None) == variation_from_scene(with_section)
    assert variation_for(with_section, None).axis("yaw_deg").bound == 2.0
    without = load_small_scene("a", 0.25, variation=None)
    assert variation_for(without, f) == load_variation(f)
    with pytest.raises(VariationError) as err:
        variation_for(without, None)
    assert err.value.file == without.source and err.value.key == "variation"
    assert "--variation FILE" in err.value.message and "\n" not in str(err.value)
