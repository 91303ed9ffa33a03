"""The same scene renders to the same bits in every process: labels and colour.

The draw order decided the depth test's ties (surfaces that meet or coincide) differently in
each process (rvmsim.render.gl._draw_in_part_order), so each case here renders in fresh
interpreters and compares their images bit for bit."""

from __future__ import annotations

import os
import runpy
import subprocess
import sys
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from rvmsim.render import cached_render
from rvmsim.testing.scenes import load_small_scene, write_small_scene

#: Draws six pairs of coincident quads (the sides of a 10 m cube around the camera), each
#: pair's two parts with their own label, alternating which of the two is listed first.
_COINCIDENT = """
import sys
import numpy as np
import trimesh
from rvmsim.render import cube_layout, render_faces
from rvmsim.scene import Part
from rvmsim.testing.scenes import load_small_scene

scene = load_small_scene("a", 0.1)
cam = scene.fisheye_camera()
box = trimesh.creation.box(extents=(10.0, 10.0, 10.0))
box.apply_translation(cam.position)
parts = []
for side, facet in enumerate(box.facets):
    quad = trimesh.Trimesh(box.vertices, box.faces[facet], process=False)
    pair = [Part(f"a{side}", 10 + side, quad, (0.2, 0.5, 0.8)),
            Part(f"b{side}", 30 + side, quad, (0.8, 0.5, 0.2))]
    parts += pair if side % 2 == 0 else pair[::-1]
atlas = render_faces(parts, cube_layout(cam, face_size=48), cam, sky=(0.0, 0.0, 0.0))
result = dict(labels=atlas.labels, color=atlas.color, first=[p.label for p in parts[::2]],
              second=[p.label for p in parts[1::2]])
if __name__ == "__main__":
    np.savez(sys.argv[1], **result)
"""


def _env(tmp_path: Path) -> dict[str, str]:
    return {**os.environ, "RVMSIM_CACHE": str(tmp_path / "cache")}


def test_coincident_surfaces_show_the_part_listed_first_in_every_process(tmp_path):
    """Where two parts coincide exactly, the one listed first in the scene's parts is seen,
    whole, in a fresh interpreter and in this test's render worker, and their atlases are
    the same bits."""
    script = tmp_path / "coincident.py"
    script.write_text(_COINCIDENT)
    out = tmp_path / "atlas_fresh.npz"
    res = subprocess.run([sys.executable, str(script), str(out)], capture_output=True,
                         text=True, timeout=300, env=_env(tmp_path), cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    here = runpy.run_path(str(script))["result"]  # the same script, rendered in the worker
    atlases = [np.load(out), here]
    for a in atlases:
        seen = set(np.unique(a["labels"]).tolist())
        assert len(seen & set(np.asarray(a["first"]).tolist())) >= 3, seen  # 3+ sides seen
        assert not seen & set(np.asarray(a["second"]).tolist()), seen
    np.testing.assert_array_equal(atlases[0]["labels"], atlases[1]["labels"])
    np.testing.assert_array_equal(atlases[0]["color"], atlases[1]["color"])


def test_a_fresh_render_is_the_cached_render_bit_for_bit(tmp_path, monkeypatch):
    """Vehicle D (its garnish against its bumper, the cylinders' bases on the ground) on a
    quarter of its sensor: rendered into an empty cache by this test's render worker, and
    by ``rvmsim render`` (always a fresh render) in a fresh interpreter: the same labels
    and colour, bit for bit."""
    scene_file = write_small_scene(tmp_path, "d")
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path / "cache"))
    cached, from_cache = cached_render(load_small_scene("d"))
    assert not from_cache
    env = {**os.environ, "RVMSIM_CACHE": str(tmp_path / "other cache")}
    out = tmp_path / "fresh"
    res = subprocess.run([sys.executable, "-m", "rvmsim", "render", str(scene_file),
                          "--out", str(out), "--no-progress"], capture_output=True,
                         text=True, timeout=300, env=env, cwd=tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    np.testing.assert_array_equal(iio.imread(out / "fisheye_labels.png"), cached.labels)
    np.testing.assert_array_equal(iio.imread(out / "fisheye_color.png"), cached.color)
