"""Cubes rendered from other viewpoints of a scene, for production-variation samples.

A camera turned about its centre needs no render: its image is a re-fold of the cube
rendered at that centre (:func:`~rvmsim.render.refold_layout`).  A camera moved, or a body
lowered and pitched by a load, changes what is seen: such a *viewpoint* is rendered once,
as the atlas of a covering layout (:func:`~rvmsim.render.cover_layout`), and stored in the
render cache as PNGs (no pickle): ``<cache>/<key>/cube_labels.png``, ``cube_color.png``
(when colour was asked for), ``cube.json``.  The key (:func:`cube_key`) hashes the scene's render key
(:func:`~rvmsim.render.scene_key`), the camera pose, the body pose, the face size and the
crops.

Conventions
-----------
``body_pose`` is a (4, 4) rigid transform of the scene frame applied to the vehicle's parts
(bumper, garnish, trunk, extra meshes): the body moved relative to the ground and test site.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..scene import Part, Scene, build_parts
from .cache import cache_dir, scene_key
from .cube import CubeLayout
from .gl import render_faces

__all__ = ["posed_parts", "cube_key", "cached_cube", "read_cube", "is_vehicle_label"]


def is_vehicle_label(label: int) -> bool:
    """Whether a label belongs to the vehicle's body (moves with it under load)."""
    return label in (L.BUMPER, L.GARNISH, L.TRUNK) or label >= L.EXTRA_PART_BASE


def posed_parts(parts: list[Part], body_pose: np.ndarray | None) -> list[Part]:
    """``parts`` with the vehicle's parts moved by ``body_pose`` ((4, 4), scene frame);
    the others (ground, test site) unchanged.  The input parts are not modified."""
    if body_pose is None or np.allclose(body_pose, np.eye(4), atol=0.0):
        return parts
    pose = np.asarray(body_pose, dtype=np.float64)
    return [dataclasses.replace(p, mesh=p.mesh.copy().apply_transform(pose))
            if is_vehicle_label(p.label) else p for p in parts]


def cube_key(scene: Scene, camera: FisheyeCamera, layout: CubeLayout,
             body_pose: np.ndarray | None = None, scale: float = 1.0) -> str:
    """Hash of what a viewpoint's cube depends on (see the module docstring): 24 hex digits."""
    rot = camera.rotation @ layout.cube_rotation
    doc = {"scene": scene_key(scene, scale), "position": np.round(camera.position, 9).tolist(),
           "rotation": np.round(rot, 12).tolist(), "face_size": layout.face_size,
           "crops": [dataclasses.astuple(c) for c in layout.crops],
           "body_pose": None if body_pose is None else np.round(body_pose, 12).tolist()}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:24]


def _read(folder: Path, shape: tuple[int, int],
          color: bool) -> tuple[np.ndarray | None, np.ndarray] | None:
    """The stored (colour or None, labels), or None if absent, damaged or of the wrong size.
    Labels are decoded with OpenCV (faster than pillow for one channel)."""
    import cv2
    import imageio.v3 as iio

    color_p, labels_p = folder / "cube_color.png", folder / "cube_labels.png"
    if not labels_p.is_file() or (color and not color_p.is_file()):
        return None
    try:
        img = np.asarray(iio.imread(color_p, plugin="pillow")) if color else None
        labels = cv2.imread(str(labels_p), cv2.IMREAD_UNCHANGED)
        if labels is None:
            raise ValueError("not a PNG OpenCV can read")
    except (OSError, ValueError) as err:
        warnings.warn(f"{folder}: damaged cube cache entry, rendering again ({err})",
                      RuntimeWarning, stacklevel=3)
        return None
    if (img is not None and img.shape[:2] != shape) or labels.shape != shape:
        return None
    return img, labels


def read_cube(scene: Scene, camera: FisheyeCamera, layout: CubeLayout, *,
              body_pose: np.ndarray | None = None, scale: float = 1.0,
              color: bool = True) -> tuple[np.ndarray | None, np.ndarray] | None:
    """The cached atlas of a viewpoint (as :func:`cached_cube`), or None when it is not in
    the cache; never renders (so it may run in a thread, e.g. to read ahead)."""
    return _read(cache_dir() / cube_key(scene, camera, layout, body_pose, scale),
                 layout.atlas_shape, color)


def cached_cube(scene: Scene, camera: FisheyeCamera, layout: CubeLayout, *,
                body_pose: np.ndarray | None = None, scale: float = 1.0,
                parts: Callable[[], list[Part]] | None = None, color: bool = True,
                progress: bool = False) -> tuple[np.ndarray | None, np.ndarray, bool]:
    """The rendered atlas of ``layout`` seen by ``camera`` (its pose; its lens is not used),
    with the body at ``body_pose``: from the cache, or rendered and stored.

    Parameters
    ----------
    scene : Scene
    camera : FisheyeCamera
        Places the cube (position, rotation).
    layout : CubeLayout
        Faces and crops to render (e.g. :func:`~rvmsim.render.cover_layout`).
    body_pose : (4, 4) float, optional
        Rigid motion of the vehicle's parts (:func:`posed_parts`).
    scale : float
        Fraction of the sensor the camera has (part of the key, as for
        :func:`~rvmsim.render.cached_render`).
    parts : callable, optional
        Gives ``build_parts(scene)`` (called only when rendering; lets callers build the
        scene's meshes, the slow part of a first render, once for many viewpoints).
    color : bool
        The colour atlas too.  Without it only the labels are rendered (half the work) and
        stored; a later call asking for colour renders the viewpoint again, with colour.
    progress : bool

    Returns
    -------
    color : (rows, cols, 3) uint8 or None
    labels : (rows, cols) uint8
        The atlas (0 where no geometry is hit), as :func:`~rvmsim.render.render_faces`.
    from_cache : bool

    Notes
    -----
    A cache folder that cannot be written only warns (``RuntimeWarning``).
    """
    from .._io import write_png
    from ..errors import RvmsimError

    folder = cache_dir() / cube_key(scene, camera, layout, body_pose, scale)
    entry = _read(folder, layout.atlas_shape, color)
    if entry is not None:
        return entry[0], entry[1], True
    base = build_parts(scene) if parts is None else parts()
    atlas = render_faces(posed_parts(base, body_pose), layout, camera,
                         sky=scene.render.sky_color, progress=progress, color=color)
    try:
        write_png(folder / "cube_labels.png", atlas.labels)
        if color:
            write_png(folder / "cube_color.png", atlas.color)
        (folder / "cube.json").write_text(json.dumps(
            {"scene": scene.source, "position": camera.position.tolist(),
             "face_size": layout.face_size, "faces": list(layout.faces)}, indent=2))
    except (OSError, RvmsimError) as err:
        warnings.warn(f"{folder}: cannot store the cube in the cache ({err})",
                      RuntimeWarning, stacklevel=2)
    return (atlas.color if color else None), atlas.labels, False
