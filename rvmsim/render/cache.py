"""On-disk cache of rendered fisheye images, keyed by what the rendering depends on.

A tuning run renders its scene once; re-runs (and resumed runs) read the images back.  The
key (:func:`scene_key`) hashes the validated scene's content (every key, with defaults filled
in, so comments and formatting do not count; the ``load_state`` too), the bytes of every mesh file it names (not
their paths: the same scene loaded from another folder hits the same entry), the render scale
and the renderer's version, so changing any of them renders again.  Images are PNGs (no
pickle): ``<cache>/<key>/fisheye_color.png``, ``fisheye_labels.png``, ``camera.json``.

The cache folder is ``$RVMSIM_CACHE`` if set, else ``~/.cache/rvmsim/render``.
"""

from __future__ import annotations

import hashlib
import json
import os
import warnings
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from .._io import write_png
from ..errors import RvmsimError
from ..scene import DEFAULT_SITE, MeshPart, Scene, mesh_parts
from .fisheye import FisheyeImages, render_fisheye

__all__ = ["cache_dir", "scene_key", "file_scene_key", "same_scene", "cached_render",
           "RENDER_VERSION"]

#: Bump when the renderer's output changes for the same scene.
RENDER_VERSION = "render-4"


def cache_dir() -> Path:
    """The cache folder: ``$RVMSIM_CACHE``, else ``~/.cache/rvmsim/render``."""
    env = os.environ.get("RVMSIM_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "rvmsim" / "render"


def _file_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def scene_key(scene: Scene, scale: float = 1.0) -> str:
    """Hash of everything the rendered images depend on: the scene's content and its mesh
    files' bytes (see the module docstring).  Needs no scene file: a scene built from a
    dictionary has a key too.

    Parameters
    ----------
    scene : Scene
    scale : float
        Fraction of the sensor size that is rendered.

    Returns
    -------
    str
        24 hex digits.
    """
    doc = scene.model_dump(mode="json")
    site = doc.get("test_site", {})
    if site.get("site") == DEFAULT_SITE and not site.get("site_objects"):
        # the FMVSS site, as before sites existed: its keys (and cached renders) unchanged
        site.pop("site", None)
        site.pop("site_objects", None)
    if not site.get("painted_lines"):  # scenes without painted lines keep their keys
        site.pop("painted_lines", None)
    if scene.load_state is not None:  # not dumped (unloaded scenes keep their keys)
        doc["load_state"] = scene.load_state.model_dump(mode="json")
    for key, part in mesh_parts(scene):
        node = doc
        *path, last = key.split(".")
        for p in path:
            node = node[int(p)] if isinstance(node, list) else node[p]
        node[last] = "sha256:" + _file_digest(scene.resolve_path(part.mesh))
    h = hashlib.sha256()
    h.update(RENDER_VERSION.encode())
    h.update(f"scale={scale!r}".encode())
    h.update(json.dumps(doc, sort_keys=True, separators=(",", ":")).encode())
    return h.hexdigest()[:24]


def file_scene_key(scene: Scene, scene_file: str | Path, scale: float = 1.0) -> str:
    """The key of rvmsim 0.1's first layout: the scene *file's* bytes and its mesh files'.

    Run folders recorded it as their scene's fingerprint before :func:`scene_key` existed;
    it is kept only to recognise those runs' scenes as unchanged.
    """
    h = hashlib.sha256()
    h.update(RENDER_VERSION.encode())
    h.update(f"scale={scale!r}".encode())
    h.update(Path(scene_file).read_bytes())
    v = scene.vehicle
    parts = [] if v is None else [v.bumper, v.garnish, v.trunk, *v.extra]
    for part in parts:
        if isinstance(part, MeshPart):
            h.update(scene.resolve_path(part.mesh).read_bytes())
    return h.hexdigest()[:24]


def _read_entry(folder: Path, width: int, height: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The cached (colour, labels) in ``folder``, or None if absent, damaged or of the wrong
    size (a damaged entry is rendered again, with a warning)."""

    color_p, labels_p = folder / "fisheye_color.png", folder / "fisheye_labels.png"
    if not (color_p.is_file() and labels_p.is_file()):
        return None
    try:
        # pillow only (imageio's first choice for PNG): its fallback plugins leave a damaged
        # file open
        color = np.asarray(iio.imread(color_p, plugin="pillow"))
        labels = np.asarray(iio.imread(labels_p, plugin="pillow"))
    except (OSError, ValueError) as err:
        warnings.warn(f"{folder}: damaged render cache entry, rendering again ({err})",
                      RuntimeWarning, stacklevel=3)
        return None
    if color.shape[:2] != (height, width) or labels.shape != (height, width):
        return None
    return color, labels


def cached_render(scene: Scene, *, scale: float = 1.0,
                  progress: bool = False) -> tuple[FisheyeImages, bool]:
    """Render ``scene`` or read it from the cache.

    Parameters
    ----------
    scene : Scene
    scale : float
        Fraction of the sensor size to render.
    progress : bool
        Progress bar while rendering.

    Returns
    -------
    images : FisheyeImages
    from_cache : bool
        True if the images came from the cache.

    Notes
    -----
    A cache folder that cannot be written (read-only, full disk) does not stop the caller:
    the images are returned and a ``RuntimeWarning`` says why they were not stored.
    """

    cam = scene.fisheye_camera()
    if scale != 1.0:
        cam = cam.scaled(scale)
    folder = cache_dir() / scene_key(scene, scale)
    entry = _read_entry(folder, cam.width, cam.height)
    if entry is not None:
        return FisheyeImages(color=entry[0], labels=entry[1], camera=cam, scene=scene), True
    images = render_fisheye(scene, camera=cam, progress=progress)
    try:
        write_png(folder / "fisheye_color.png", images.color)
        write_png(folder / "fisheye_labels.png", images.labels)
        (folder / "camera.json").write_text(json.dumps(
            {"scene": scene.source, "K": cam.K.tolist(), "D": cam.D.ravel().tolist(),
             "lens_model": cam.lens_model, "size": [cam.width, cam.height]}, indent=2))
    except (OSError, RvmsimError) as err:
        warnings.warn(f"{folder}: cannot store the render in the cache ({err})",
                      RuntimeWarning, stacklevel=2)
    return images, False


def same_scene(recorded_key: str, scene: Scene, scene_file: str | Path) -> bool:
    """Whether a fingerprint recorded in a run folder is that of ``scene`` as it is now:
    :func:`scene_key`, or (for runs recorded before it) :func:`file_scene_key`."""
    if recorded_key == scene_key(scene):
        return True
    return Path(scene_file).is_file() and recorded_key == file_scene_key(scene, scene_file)
