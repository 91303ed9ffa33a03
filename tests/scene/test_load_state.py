"""A scene's ``load_state``: the body and camera moved exactly as robustness moves a
loaded sample, seen by everything that reads the scene's camera and parts, and part of the
render cache's key."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.errors import SceneError
from rvmsim.render import posed_parts, render_fisheye, scene_key
from rvmsim.robust import LoadState, MountSample, body_pose, robustness, sample_camera
from rvmsim.robust import RobustnessSettings
from rvmsim.isp import IspParams
from rvmsim.scene import build_parts, scene_from_dict

from rvmsim.testing.scenes import load_small_scene, small_scene_doc
from .conftest import minimal_scene

FULL = {"name": "full load", "height_mm": -45.0, "pitch_deg": 0.9}
LOAD = LoadState("full load", -45.0, 0.9)


def _same_parts(a, b) -> None:
    assert [p.label for p in a] == [p.label for p in b]
    for pa, pb in zip(a, b):
        np.testing.assert_array_equal(pa.mesh.vertices, pb.mesh.vertices)


def test_a_loaded_scene_is_robustness_loaded_sample():
    """Camera pose and every part's vertices equal, to the bit, what robustness gives a
    sample in that load state with no mount offset."""
    plain = load_small_scene("a", variation=None)
    loaded = load_small_scene("a", variation=None, edit={"load_state": FULL})
    sample = MountSample(0, (0.0,) * 6, (0.0, 0.0, 0.0), LOAD)
    cam, ref = loaded.fisheye_camera(), sample_camera(plain, sample)
    np.testing.assert_array_equal(cam.rotation, ref.rotation)
    np.testing.assert_array_equal(cam.position, ref.position)
    _same_parts(build_parts(loaded), posed_parts(build_parts(plain), body_pose(plain, LOAD)))
    # the site stays, the body moves: lower by 45 mm at the camera, rear down
    moved = {p.label: p for p in build_parts(loaded)}
    still = {p.label: p for p in build_parts(plain)}
    np.testing.assert_array_equal(moved[L.GROUND].mesh.vertices, still[L.GROUND].mesh.vertices)
    assert moved[L.BUMPER].mesh.bounds[1][1] > still[L.BUMPER].mesh.bounds[1][1] + 0.03
    assert cam.position[1] - plain.fisheye_camera().position[1] == pytest.approx(0.045)


def test_a_moved_mount_with_the_nominal_pivot_is_a_sample_with_an_offset():
    """A sample's offsets folded into the mount, the body pitching about the nominal centre
    (``pivot_m``): the sample's camera and body exactly."""
    plain = load_small_scene("a", variation=None)
    m = plain.camera.mount
    d_mm, d_deg = (2.5, -2.5, 2.5), (0.3, -0.7, 0.5)
    mount = {"position": [p + d / 1000.0 for p, d in zip(m.position, d_mm)],
             "yaw_deg": m.yaw_deg + d_deg[0], "pitch_deg": m.pitch_deg + d_deg[1],
             "roll_deg": m.roll_deg + d_deg[2]}
    moved = load_small_scene("a", variation=None, edit={
        "camera.mount": mount, "load_state": {**FULL, "pivot_m": list(m.position)}})
    sample = MountSample(0, (*d_mm, *d_deg), d_mm, LOAD)
    cam, ref = moved.fisheye_camera(), sample_camera(plain, sample)
    np.testing.assert_allclose(cam.rotation, ref.rotation, rtol=0, atol=1e-15)
    np.testing.assert_allclose(cam.position, ref.position, rtol=0, atol=1e-15)
    _same_parts(build_parts(moved), posed_parts(build_parts(plain), body_pose(plain, LOAD)))


def test_the_render_and_its_cache_key_see_the_load():
    plain = load_small_scene("a", 0.125, variation=None)
    loaded = load_small_scene("a", 0.125, variation=None, edit={"load_state": FULL})
    assert "load_state" not in plain.model_dump()  # unloaded scenes keep their keys
    assert scene_key(loaded) != scene_key(plain)
    other = load_small_scene("a", 0.125, variation=None,
                             edit={"load_state": {**FULL, "pitch_deg": 1.0}})
    assert scene_key(other) != scene_key(loaded)
    img = render_fisheye(loaded)
    np.testing.assert_array_equal(img.camera.rotation, loaded.fisheye_camera().rotation)
    base = render_fisheye(plain)
    # the body moves with the camera: the bumper stays about where it was in the image,
    # the ground (which does not move) shifts by the drop and pitch
    bumper = [np.mean(i.labels == L.BUMPER) for i in (base, img)]
    assert bumper[1] == pytest.approx(bumper[0], rel=0.1)
    assert np.mean(base.labels != img.labels) > 0.01


@pytest.mark.parametrize("key,value,words", [
    ("height_mm", -400.0, "greater than or equal to -300"),
    ("height_mm", 301.0, "less than or equal to 300"),
    ("pitch_deg", 12.0, "less than or equal to 10"), ("pitch_deg", float("nan"), "finite"),
    ("weight", 0.5, "unknown key"), ("name", "", "at least 1"),
])
def test_a_bad_load_state_names_its_key(key, value, words):
    doc = {**minimal_scene(), "load_state": {**FULL, key: value}}
    with pytest.raises(SceneError, match=f"load_state.{key}") as err:
        scene_from_dict(doc, source="s.yaml")
    assert str(err.value).startswith("s.yaml: ") and words in str(err.value)


def test_robustness_refuses_a_loaded_scene():
    loaded = load_small_scene("a", variation=small_scene_doc("a")["variation"],
                              edit={"load_state": FULL})
    with pytest.raises(SceneError, match="load_state: a scene with a load state"):
        robustness(loaded, IspParams().for_input_scale(0.25),
                   RobustnessSettings(samples=2, scales=(1.0,)), frames=False)
