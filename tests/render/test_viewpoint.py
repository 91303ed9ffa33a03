"""rvmsim.render.render_cubes: viewpoints rendered up front (here or on a runner), stored in
the render cache exactly as cached_cube renders and stores them."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvmsim.batch import LocalExecutor
from rvmsim.render import CubeView, cached_cube, cube_key, render_cubes
from rvmsim.robust import body_pose, cover_for, draw_samples, variation_from_scene
from rvmsim.robust.images import viewpoint_groups

from rvmsim.testing.scenes import load_small_scene

VARIATION = {"mount": {"x_mm": {"uniform": {"half_width": 5}},
                       "yaw_deg": {"uniform": {"half_width": 1.0}}},
             "load_states": [{"name": "curb", "height_mm": 0, "pitch_deg": 0},
                             {"name": "full", "height_mm": -40, "pitch_deg": 0.8}]}


def _views(scene, n: int = 16) -> list[CubeView]:
    from rvmsim.robust import sample_camera
    from rvmsim.robust.samples import MountSample

    samples = draw_samples(variation_from_scene(scene), n, 0)
    cover = cover_for(scene, samples)
    views = []
    for g in viewpoint_groups(samples):
        s = samples[g[0]]
        flat = MountSample(s.index, (*s.render_position_mm, 0.0, 0.0, 0.0),
                           s.render_position_mm, s.load)
        views.append(CubeView(sample_camera(scene, flat), cover, body_pose(scene, s.load)))
    return views


@pytest.fixture()
def empty_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.mark.parametrize("workers", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_render_cubes_stores_what_cached_cube_renders(empty_cache: Path, workers: int):
    scene = load_small_scene("a", 0.25, variation=VARIATION)
    views = _views(scene)
    assert len(views) == 4  # 2 x-levels x 2 load states
    runner = LocalExecutor(workers) if workers > 1 else None
    assert render_cubes(scene, [*views, views[0]], runner=runner) == 4  # repeats once
    keys = {cube_key(scene, v.camera, v.layout, v.body_pose) for v in views}
    assert {p.name for p in empty_cache.iterdir()} == keys
    assert not list(empty_cache.glob("*/.*.tmp"))  # no temporary file left behind
    assert render_cubes(scene, views, runner=runner) == 0  # all cached now
    for v in views[:2]:
        _, stored, from_cache = cached_cube(scene, v.camera, v.layout, body_pose=v.body_pose,
                                            color=False)
        assert from_cache
        # an independent render of the same view, not through the cache
        fresh = empty_cache.parent / "fresh"
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("RVMSIM_CACHE", str(fresh))
            _, rendered, hit = cached_cube(scene, v.camera, v.layout, body_pose=v.body_pose,
                                           color=False)
        assert not hit and stored.shape == rendered.shape
        # the same view: equal but for a stray pixel where GL rasterises an edge exactly
        # between two triangles (seen: 1 in 10^6, at a label border)
        assert (stored != rendered).mean() < 1e-4
        assert (stored > 0).mean() > 0.5  # the atlas holds geometry, not only sky


def test_colour_is_rendered_when_asked_for_after_labels(empty_cache: Path):
    scene = load_small_scene("a", 0.25, variation=VARIATION)
    v = _views(scene)[0]
    assert render_cubes(scene, [v]) == 1
    assert render_cubes(scene, [v], color=True) == 1  # labels only were stored
    color, labels, hit = cached_cube(scene, v.camera, v.layout, body_pose=v.body_pose)
    assert hit and color is not None and color.shape == (*labels.shape, 3)
    assert color.reshape(-1, 3).std(axis=0).min() > 5  # a real picture


def test_an_unwritable_cache_only_warns(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("RVMSIM_CACHE", str(blocker))
    scene = load_small_scene("a", 0.25, variation=VARIATION)
    with pytest.warns(RuntimeWarning, match="cannot store the cube"):
        assert render_cubes(scene, _views(scene)[:1]) == 1
