"""Cubes rendered from other viewpoints of a scene, for production-variation samples.

A camera turned about its centre needs no render: its image is a re-fold of the cube
rendered at that centre (:func:`~rvmsim.render.refold_layout`).  A camera moved, or a body
lowered and pitched by a load, changes what is seen: such a *viewpoint* is rendered once,
as the atlas of a covering layout (:func:`~rvmsim.render.cover_layout`), and stored in the
render cache as PNGs (no pickle): ``<cache>/<key>/cube_labels.png``, ``cube_color.png``
(when colour was asked for), ``cube.json``.  The key (:func:`cube_key`) hashes the scene's render key
(:func:`~rvmsim.render.scene_key`), the camera pose, the body pose, the face size and the
crops.

Viewpoints not yet in the cache can be rendered in parallel first
(:func:`render_cubes`): one task per viewpoint (:func:`cube_task`) on any runner with the
``run(fn, items)`` interface of ``rvmsim.batch``'s executors (local processes, a Dask
cluster); each task returns its atlas as PNG bytes, which are stored here.

Conventions
-----------
``body_pose`` is a (4, 4) rigid transform of the scene frame applied to the vehicle's parts
(bumper, garnish, trunk, extra meshes): the body moved relative to the ground and test site.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, TypedDict, TypeVar

import cv2
import imageio.v3 as iio
import numpy as np

from .. import labels as L
from .._progress import progress_bar
from ..camera import FisheyeCamera
from ..scene import Part, Scene, build_parts
from .cache import cache_dir, scene_key
from .cube import CubeLayout
from .gl import RenderProcess, render_faces

__all__ = ["posed_parts", "cube_key", "cached_cube", "read_cube", "is_vehicle_label",
           "CubeView", "TaskRunner", "render_cubes", "cube_task"]


def is_vehicle_label(label: int) -> bool:
    """Whether a label belongs to the vehicle's body (moves with it under load)."""
    return label in L.BODY_LABELS


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
                progress: bool = False, renders: RenderProcess | None = None
                ) -> tuple[np.ndarray | None, np.ndarray, bool]:
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
    renders : RenderProcess, optional
        The render worker kept for a block of viewpoints (:func:`~rvmsim.render.render_faces`).

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
    folder = cache_dir() / cube_key(scene, camera, layout, body_pose, scale)
    entry = _read(folder, layout.atlas_shape, color)
    if entry is not None:
        return entry[0], entry[1], True
    base = build_parts(scene) if parts is None else parts()
    atlas = render_faces(posed_parts(base, body_pose), layout, camera,
                         sky=scene.render.sky_color, progress=progress, color=color,
                         renders=renders)
    _store(folder, scene, camera, layout, _png(atlas.labels),
           _png(atlas.color) if color else None)
    return (atlas.color if color else None), atlas.labels, False


def _png(image: np.ndarray) -> bytes:
    """PNG bytes of an (H, W) or RGB (H, W, 3) uint8 image (OpenCV's encoder, fast level)."""

    img = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(img), [cv2.IMWRITE_PNG_COMPRESSION, 1])
    if not ok:
        raise ValueError("OpenCV could not encode the atlas as PNG")
    return buf.tobytes()


def _store(folder: Path, scene: Scene, camera: FisheyeCamera, layout: CubeLayout,
           labels_png: bytes, color_png: bytes | None) -> None:
    """Write a cube's PNGs (each through a temporary file and a rename, so a reader never
    sees half a file) and its ``cube.json``; a folder that cannot be written only warns."""
    files = {"cube_labels.png": labels_png, "cube.json": json.dumps(
        {"scene": scene.source, "position": camera.position.tolist(),
         "face_size": layout.face_size, "faces": list(layout.faces)}, indent=2).encode()}
    if color_png is not None:
        files["cube_color.png"] = color_png
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for name, data in files.items():
            tmp = folder / f".{name}.{os.getpid()}.tmp"
            tmp.write_bytes(data)
            os.replace(tmp, folder / name)
    except OSError as err:
        warnings.warn(f"{folder}: cannot store the cube in the cache ({err.strerror or err})",
                      RuntimeWarning, stacklevel=3)


@dataclass(frozen=True)
class CubeView:
    """One viewpoint to render: ``camera`` places the cube (its pose; the lens is not used),
    ``layout`` gives the faces and crops, ``body_pose`` moves the vehicle's parts."""

    camera: FisheyeCamera
    layout: CubeLayout
    body_pose: np.ndarray | None = None


#: A task's argument and its result (a task function maps one to the other).
_Arg = TypeVar("_Arg")
_Result = TypeVar("_Result")


class TaskRunner(Protocol):
    """Anything that runs ``fn(arg)`` for every item of ``items`` and yields ``(key,
    result)`` as tasks finish (``rvmsim.batch.LocalExecutor``, ``DaskExecutor``)."""

    def run(self, fn: Callable[[_Arg], _Result], items: Mapping[str, _Arg]
            ) -> Iterator[tuple[str, _Result]]:
        ...


class CubeTask(TypedDict):
    """:func:`cube_task`'s argument: the scene, the view, and whether to render colour."""

    scene: Scene
    view: CubeView
    color: bool


class CubePngs(TypedDict):
    """:func:`cube_task`'s result: the label atlas and the colour atlas (None: not asked
    for) as PNG bytes."""

    labels: bytes
    color: bytes | None


def cube_task(task: CubeTask) -> CubePngs:
    """Render one viewpoint (a task for a worker process or a cluster worker).

    ``task``: ``scene`` (Scene), ``view`` (:class:`CubeView`), ``color`` (bool).  Returns
    ``{"labels": PNG bytes, "color": PNG bytes or None}`` (the atlas, as
    :func:`cached_cube` stores it).
    """
    scene, view = task["scene"], task["view"]
    atlas = render_faces(posed_parts(build_parts(scene), view.body_pose), view.layout,
                         view.camera, sky=scene.render.sky_color, color=bool(task["color"]))
    return {"labels": _png(atlas.labels),
            "color": _png(atlas.color) if task["color"] else None}


def render_cubes(scene: Scene, views: Sequence[CubeView], *, scale: float = 1.0,
                 color: bool = False, runner: TaskRunner | None = None,
                 progress: bool = False) -> int:
    """Render, and store in the render cache, every view of ``views`` not already there.

    Parameters
    ----------
    scene : Scene
    views : sequence of CubeView
        Repeats are rendered once.
    scale : float
        Fraction of the sensor (part of the cache key, as for :func:`cached_cube`).
    color : bool
        The colour atlas too (else labels only).
    runner : TaskRunner, optional
        Where the renders run (one task per view); default: one after another here.
    progress : bool

    Returns
    -------
    int
        Views rendered (those found in the cache are not counted).

    Notes
    -----
    A view counts as cached when its PNG files exist; a damaged entry is found (and
    rendered again) when it is read.  Workers need the scene's mesh files at the same
    paths.
    """
    todo: dict[str, CubeView] = {}
    for v in views:
        key = cube_key(scene, v.camera, v.layout, v.body_pose, scale)
        folder = cache_dir() / key
        have = (folder / "cube_labels.png").is_file() and (
            not color or (folder / "cube_color.png").is_file())
        if not have:
            todo.setdefault(key, v)
    if not todo:
        return 0
    items: dict[str, CubeTask] = {k: {"scene": scene, "view": v, "color": color}
                                  for k, v in todo.items()}
    results = runner.run(cube_task, items) if runner is not None else (
        (k, cube_task(t)) for k, t in items.items())
    bar = None
    if progress:
        bar = progress_bar(total=len(items), desc="render viewpoints", unit="view", leave=False)
    try:
        for key, out in results:
            v = todo[key]
            labels_png, color_png = out["labels"], out["color"]
            if not isinstance(labels_png, bytes):
                raise TypeError(f"render task {key} returned no label PNG")
            _store(cache_dir() / key, scene, v.camera, v.layout, labels_png, color_png)
            if bar is not None:
                bar.update(1)
    finally:
        if bar is not None:
            bar.close()
    return len(items)
