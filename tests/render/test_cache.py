"""The render cache: keyed on the scene's content and mesh bytes; damaged or unwritable
entries warn and fall back to rendering (real small renders)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest
import yaml

from rvmsim.render import cache_dir, cached_render, file_scene_key, same_scene, scene_key
from rvmsim.scene import absolute_mesh_paths, load_scene, scene_from_dict

from ..conftest import SCENES

SCALE = 0.1


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


def test_key_follows_content_not_text_or_folder(tmp_path):
    path = SCENES / "vehicle_a.yaml"
    scene = load_scene(path)
    text = path.read_text()
    copy = tmp_path / "a.yaml"
    copy.write_text("# a comment does not count\n" + text)
    assert scene_key(load_scene(copy)) == scene_key(scene)
    assert scene_key(scene, 0.5) != scene_key(scene)
    doc = yaml.safe_load(text)
    # the production variation (its least yield too) changes no picture
    assert scene.variation is not None and "min_yield" not in doc["variation"]
    doc["variation"]["min_yield"] = 0.9
    assert scene_key(scene_from_dict(doc)) == scene_key(scene)
    doc = yaml.safe_load(text)
    doc["camera"]["mount"]["pitch_deg"] += 0.5
    assert scene_key(scene_from_dict(doc)) != scene_key(scene)


def test_key_hashes_mesh_bytes_not_paths(tmp_path):
    doc = yaml.safe_load((SCENES / "vehicle_f.yaml").read_text())
    (mesh,) = absolute_mesh_paths(doc, SCENES)
    key = scene_key(scene_from_dict(doc))
    moved = tmp_path / "moved.stl"
    shutil.copy(mesh, moved)
    doc["vehicle"]["bumper"]["mesh"] = str(moved)
    assert scene_key(scene_from_dict(doc)) == key
    moved.write_bytes(moved.read_bytes() + b"\n")
    assert scene_key(scene_from_dict(doc)) != key


def test_cached_render_round_trip_and_damaged_entry(cache):
    scene = load_scene(SCENES / "vehicle_a.yaml")
    first, hit = cached_render(scene, scale=SCALE)
    assert not hit and cache_dir() == cache
    again, hit = cached_render(scene, scale=SCALE)
    assert hit
    np.testing.assert_array_equal(again.color, first.color)
    np.testing.assert_array_equal(again.labels, first.labels)
    np.testing.assert_array_equal(again.camera.K, first.camera.K)
    entry = cache / scene_key(scene, SCALE)
    (entry / "fisheye_color.png").write_bytes(b"not a png")
    with pytest.warns(RuntimeWarning, match="damaged render cache entry"):
        redone, hit = cached_render(scene, scale=SCALE)
    assert not hit
    np.testing.assert_array_equal(redone.labels, first.labels)


def test_unwritable_cache_warns_and_still_returns_images(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder would be")
    monkeypatch.setenv("RVMSIM_CACHE", str(blocker / "cache"))
    scene = load_scene(SCENES / "vehicle_a.yaml")
    with pytest.warns(RuntimeWarning, match="cannot store the render"):
        images, hit = cached_render(scene, scale=SCALE)
    assert not hit and images.labels.shape == (images.camera.height, images.camera.width)


def test_same_scene_accepts_both_recorded_keys(tmp_path):
    path = SCENES / "vehicle_a.yaml"
    scene = load_scene(path)
    assert same_scene(scene_key(scene), scene, path)
    assert same_scene(file_scene_key(scene, path), scene, path)
    assert not same_scene("0" * 24, scene, path)
    assert not same_scene(file_scene_key(scene, path), scene, tmp_path / "gone.yaml")
