"""On-disk cache of rendered fisheye images, keyed by what the rendering depends on.

A tuning run renders its scene once; re-runs (and resumed runs) read the images back.  The
key hashes the scene file's bytes, the bytes of every mesh file it names, the render scale
and the renderer's version, so editing any of them renders again.  Images are PNGs (no
pickle): ``<cache>/<key>/fisheye_color.png``, ``fisheye_labels.png``, ``camera.json``.

The cache folder is ``$RVMSIM_CACHE`` if set, else ``~/.cache/rvmsim/render``.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from .fisheye import FisheyeImages, render_fisheye
from ..scene.schema import MeshPart, Scene

__all__ = ["cache_dir", "scene_key", "cached_render", "RENDER_VERSION"]

#: Bump when the renderer's output changes for the same scene.
RENDER_VERSION = "render-1"


def cache_dir() -> Path:
    env = os.environ.get("RVMSIM_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "rvmsim" / "render"


def scene_key(scene: Scene, scene_file: str | Path, scale: float = 1.0) -> str:
    """Hash of everything the rendered images depend on."""
    h = hashlib.sha256()
    h.update(RENDER_VERSION.encode())
    h.update(f"scale={scale!r}".encode())
    h.update(Path(scene_file).read_bytes())
    parts = [scene.vehicle.bumper, scene.vehicle.garnish, scene.vehicle.trunk,
             *scene.vehicle.extra]
    for part in parts:
        if isinstance(part, MeshPart):
            h.update(scene.resolve_path(part.mesh).read_bytes())
    return h.hexdigest()[:24]


def cached_render(scene: Scene, scene_file: str | Path, *, scale: float = 1.0,
                  progress: bool = False) -> tuple[FisheyeImages, bool]:
    """Render ``scene`` or read it from the cache: (images, True if it came from the cache)."""
    import imageio.v3 as iio

    from .._io import write_png

    cam = scene.fisheye_camera()
    if scale != 1.0:
        cam = cam.scaled(scale)
    folder = cache_dir() / scene_key(scene, scene_file, scale)
    color_p, labels_p = folder / "fisheye_color.png", folder / "fisheye_labels.png"
    if color_p.is_file() and labels_p.is_file():
        try:
            color = np.asarray(iio.imread(color_p))
            labels = np.asarray(iio.imread(labels_p))
            if color.shape[:2] == labels.shape == (cam.height, cam.width):
                return FisheyeImages(color=color, labels=labels, camera=cam), True
        except Exception:  # a damaged cache entry is simply rendered again
            pass
    images = render_fisheye(scene, camera=cam, progress=progress)
    try:
        write_png(color_p, images.color)
        write_png(labels_p, images.labels)
        (folder / "camera.json").write_text(json.dumps(
            {"scene": str(scene_file), "K": cam.K.tolist(), "D": cam.D.ravel().tolist(),
             "size": [cam.width, cam.height]}, indent=2))
    except Exception:  # a read-only cache folder must not stop the run
        pass
    return images, False
