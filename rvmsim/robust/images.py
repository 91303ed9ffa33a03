"""Fisheye images of variation samples: exact rotations by re-folding, few renders.

Method
------
* A mount rotation turns the camera about its optical centre, so its image is a re-fold of
  the cube rendered at that centre (:func:`rvmsim.render.refold_layout`): no render.  The
  cube's crops cover every sample's rotation (:func:`rvmsim.render.cover_layout`, over a
  grid spanning the samples' angle ranges).
* A load state moves the body (camera and vehicle parts together) relative to the ground:
  the body pitches about the camera's nominal centre by ``pitch_deg`` (rear down > 0) and the
  camera's height changes by ``height_mm``.  A mount position offset moves the camera relative
  to the body.  Both change the viewpoint, which is rendered once per distinct (rendered
  position, load state) and kept in the render cache (:func:`rvmsim.render.cached_cube`).
  Positions are rendered at the sample's ``render_position_mm`` (a few levels per axis, see
  :mod:`rvmsim.robust.samples`); docs/robustness.md states the landmark error this costs.

The images of a sample are the rotated camera's, at the rendered position: a sample's
evaluation then costs what a tuning candidate's does.

Conventions
-----------
Camera-to-scene rotation of a sample: ``R_b · R(yaw + δyaw, pitch + δpitch, roll + δroll)``
with ``R_b`` the body pitch (:func:`~rvmsim.camera.rotation_from_ypr` (0, pitch_deg, 0));
position ``p₀ + R_b · δp + (0, −height_mm, 0)`` (scene frame, Y toward the ground, mm → m).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .. import labels as L
from .._progress import progress_bar
from ..camera import FisheyeCamera, rotation_from_ypr
from ..errors import SceneError
from ..pipeline import FisheyeLabels, RvmPixels
from ..render import (CameraRays, CubeLayout, CubeView, FisheyeImages, RenderProcess,
                      TaskRunner, cached_cube,
                      cover_layout, fold, fold_labels, nearest_labels, read_cube, refold_coords,
                      refold_layout, render_cubes)
from ..scene import Scene, body_motion, build_parts
from .samples import MountSample
from .variation import LoadState

if TYPE_CHECKING:
    from .._progress import ProgressBar

__all__ = ["sample_images", "Refolder", "refolder", "SampleSet", "sample_rvm_labels",
           "viewpoint_groups", "sample_camera", "body_pose", "cover_for", "ANGLE_STEP_DEG",
           "render_viewpoints"]

#: The covered angle ranges are rounded up to this step (degrees), so that sample sets of
#: about the same spread share cached cubes.
ANGLE_STEP_DEG = 0.5


def _body_rotation(load: LoadState) -> np.ndarray:
    return rotation_from_ypr(0.0, load.pitch_deg, 0.0)


def _unloaded(scene: Scene) -> None:
    """Samples carry their own load states: a scene with one (a single loaded car, e.g. an
    exported sample) is refused rather than loaded twice."""
    if scene.load_state is not None:
        raise SceneError(scene.source, "load_state",
                         "a scene with a load state is one loaded car; production variation "
                         "draws the load states of its variation (remove load_state)")


def body_pose(scene: Scene, load: LoadState) -> np.ndarray | None:
    """The (4, 4) rigid motion of the vehicle's parts under ``load`` (None: unmoved): the
    body pitched about the camera's nominal centre, then lowered by the camera's drop
    (:func:`rvmsim.scene.body_motion`, as a scene's ``load_state`` moves it).

    Raises
    ------
    SceneError
        When ``scene`` has a ``load_state`` of its own.
    """
    _unloaded(scene)
    if load.height_mm == 0.0 and load.pitch_deg == 0.0:
        return None
    return body_motion(load.height_mm, load.pitch_deg,
                       np.asarray(scene.camera.mount.position, dtype=np.float64))


def sample_camera(scene: Scene, sample: MountSample, *, scale: float = 1.0,
                  rendered: bool = True) -> FisheyeCamera:
    """The camera of ``sample``: its pose per the module's convention, the scene's lens at
    ``scale`` of the sensor; at the rendered position (``rendered``) or the drawn one.

    Raises
    ------
    SceneError
        When ``scene`` has a ``load_state`` of its own.
    """
    _unloaded(scene)
    m = scene.camera.mount
    cam = scene.fisheye_camera()
    cam = cam.scaled(scale) if scale != 1.0 else cam
    rb = _body_rotation(sample.load)
    dy, dp, dr = sample.angles_deg
    rot = rb @ rotation_from_ypr(m.yaw_deg + dy, m.pitch_deg + dp, m.roll_deg + dr)
    d = np.asarray(sample.render_position_mm if rendered else sample.position_mm) / 1000.0
    pos = (np.asarray(m.position, dtype=np.float64) + rb @ d
           + np.array([0.0, -sample.load.height_mm / 1000.0, 0.0]))
    return dataclasses.replace(cam, rotation=rot, position=pos)


def _viewpoint_camera(scene: Scene, sample: MountSample, scale: float) -> FisheyeCamera:
    """The camera the viewpoint's cube is rendered for: the sample's rendered position and
    load, the nominal mount angles."""
    unturned = MountSample(sample.index, (*sample.render_position_mm, 0.0, 0.0, 0.0),
                           sample.render_position_mm, sample.load, sample.scale)
    return sample_camera(scene, unturned, scale=scale)


def cover_for(scene: Scene, samples: Sequence[MountSample], *, scale: float = 1.0) -> CubeLayout:
    """The covering layout for ``samples``' rotations: a 5-level grid over each angle's
    range (the samples' largest offset rounded up to :data:`ANGLE_STEP_DEG`, plus a step)."""
    _unloaded(scene)
    m = scene.camera.mount
    cam = scene.fisheye_camera()
    cam = cam.scaled(scale) if scale != 1.0 else cam
    bounds = [math.ceil(max(abs(s.angles_deg[i]) for s in samples) / ANGLE_STEP_DEG - 1e-9)
              * ANGLE_STEP_DEG for i in range(3)]
    bounds = [b + ANGLE_STEP_DEG if b > 0 else 0.0 for b in bounds]
    nominal = rotation_from_ypr(m.yaw_deg, m.pitch_deg, m.roll_deg)
    grids = [np.linspace(-b, b, 5) if b > 0 else np.zeros(1) for b in bounds]
    rotations = [rotation_from_ypr(m.yaw_deg + a, m.pitch_deg + b, m.roll_deg + c).T @ nominal
                 for a, b, c in itertools.product(*grids)]
    r = scene.render
    return cover_layout(cam, rotations, face_size=r.face_size_px, oversample=r.oversample,
                        max_face_size=r.max_face_size_px)


def _viewpoint(sample: MountSample) -> tuple[tuple[float, ...], str]:
    return tuple(round(v, 9) for v in sample.render_position_mm), sample.load.name


def viewpoint_groups(samples: Sequence[MountSample]) -> list[list[int]]:
    """The indices of ``samples`` by viewpoint (rendered position and load state): each
    group needs one render.  To render the viewpoints elsewhere (an executor), call
    :func:`sample_images` on each group's samples with the ``shared`` :func:`refolder` of
    all of them (the same covering crops, so the same cache entries)."""
    groups: dict[tuple[tuple[float, ...], str], list[int]] = {}
    for i, s in enumerate(samples):
        groups.setdefault(_viewpoint(s), []).append(i)
    return list(groups.values())


def render_viewpoints(scene: Scene, sample_sets: Sequence[Sequence[MountSample]], *,
                      scale: float = 1.0, runner: TaskRunner | None = None,
                      shared: Sequence[Refolder] | None = None, progress: bool = False) -> int:
    """Render (labels only) every viewpoint of every sample set that is not yet in the
    render cache, on ``runner`` (e.g. ``rvmsim.batch.LocalExecutor(2)`` or a Dask
    executor; default: here, one after another).  Each set gets its own covering crops
    (its :func:`refolder`, or ``shared[k]`` for set ``k``), as :func:`sample_images` and
    :func:`sample_rvm_labels` use them, so those calls then read every cube from the cache.
    Returns the number rendered."""
    views = []
    for k, samples in enumerate(sample_sets):
        if not samples:
            continue
        cover = shared[k].cover if shared is not None else cover_for(scene, samples, scale=scale)
        for g in viewpoint_groups(samples):
            s = samples[g[0]]
            views.append(CubeView(_viewpoint_camera(scene, s, scale), cover,
                                  body_pose(scene, s.load)))
    return render_cubes(scene, views, scale=scale, runner=runner, progress=progress)


@dataclass(frozen=True)
class Refolder:
    """What every re-fold of one sample set shares: the covering layout and the camera's
    pixel rays (:func:`refolder`)."""

    cover: CubeLayout
    rays: CameraRays


def refolder(scene: Scene, samples: Sequence[MountSample], *, scale: float = 1.0) -> Refolder:
    """The :class:`Refolder` of ``samples`` (build it once for many calls of
    :func:`sample_images` on parts of one sample set)."""
    cam = scene.fisheye_camera()
    return Refolder(cover_for(scene, samples, scale=scale),
                    CameraRays.of(cam.scaled(scale) if scale != 1.0 else cam))


def sample_images(scene: Scene, samples: Sequence[MountSample], *, scale: float = 1.0,
                  progress: bool = False, color: bool = True,
                  shared: Refolder | None = None) -> list[FisheyeImages]:
    """The fisheye colour and label images of every sample (see the module docstring).

    Parameters
    ----------
    scene : Scene
    samples : sequence of MountSample
        From :func:`~rvmsim.robust.draw_samples`.
    scale : float
        Fraction of the sensor to render (as :func:`rvmsim.render.cached_render`).
    progress : bool
        Progress bars over the renders and the re-folds.
    color : bool
        Also fold the colour image; without it, ``color`` is black (a read-only broadcast
        view, no memory), for evaluations that read labels only.
    shared : Refolder, optional
        :func:`refolder` of a sample set holding ``samples`` (default: of ``samples``).

    Returns
    -------
    list of FisheyeImages
        In ``samples``' order; ``camera`` is the sample's (:func:`sample_camera`, at its
        rendered position).

    Notes
    -----
    Pure apart from the render cache: the viewpoints' cubes can be rendered anywhere first
    (the same call with the same samples finds them).
    """
    if not samples:
        return []
    shared = shared if shared is not None else refolder(scene, samples, scale=scale)
    cover, rays = shared.cover, shared.rays
    out: list[FisheyeImages | None] = [None] * len(samples)
    bar = _bar(progress, len(samples), "sample images")
    for idx, view_cam, atlas_c, atlas_l in _viewpoints(scene, samples, shared, scale, color):
        for i in idx:
            cam = sample_camera(scene, samples[i], scale=scale)
            layout = refold_layout(cover, cam.rotation.T @ view_cam.rotation, rays)
            if color and atlas_c is not None:
                img_c, img_l = fold(layout, atlas_c, atlas_l, scene.render.color_filter)
            else:
                img_l = fold_labels(layout, atlas_l)
                img_c = np.broadcast_to(np.zeros(3, np.uint8), (*img_l.shape, 3))
            out[i] = FisheyeImages(color=img_c, labels=img_l, camera=cam,
                                   face_size=cover.face_size, scene=scene)
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    return [o for o in out if o is not None]


def _bar(progress: bool, total: int, desc: str) -> ProgressBar | None:
    if not progress:
        return None

    return progress_bar(total=total, desc=desc, unit="sample", leave=False)


def _viewpoints(scene: Scene, samples: Sequence[MountSample], shared: Refolder, scale: float,
                color: bool) -> Iterator[tuple[list[int], FisheyeCamera, np.ndarray | None,
                                               np.ndarray]]:
    """Per distinct viewpoint of ``samples``: the indices of its samples, the camera its cube
    is rendered for, and the cube's atlas (colour None when not asked for and cached)."""

    parts = functools.lru_cache(maxsize=1)(lambda: build_parts(scene))
    groups = viewpoint_groups(samples)
    cams = [_viewpoint_camera(scene, samples[g[0]], scale) for g in groups]
    poses = [body_pose(scene, samples[g[0]].load) for g in groups]

    def read(k: int) -> tuple[np.ndarray | None, np.ndarray] | None:
        return read_cube(scene, cams[k], shared.cover, body_pose=poses[k], scale=scale,
                         color=color)

    # the next viewpoint's cube is read (decoded) while this one's samples are re-folded;
    # the viewpoints not cached render in one kept worker
    with ThreadPoolExecutor(max_workers=1) as pool, RenderProcess() as renders:
        ahead = pool.submit(read, 0)
        for k, idx in enumerate(groups):
            entry = ahead.result()
            if k + 1 < len(groups):
                ahead = pool.submit(read, k + 1)
            if entry is None:  # not cached: render here (GL stays in this thread)
                atlas_c, atlas_l, _ = cached_cube(scene, cams[k], shared.cover, scale=scale,
                                                  parts=parts, body_pose=poses[k], color=color,
                                                  renders=renders)
            else:
                atlas_c, atlas_l = entry
            yield idx, cams[k], atlas_c, atlas_l


def sample_rvm_labels(scene: Scene, samples: Sequence[MountSample],
                      rvm: RvmPixels | Callable[[int], RvmPixels], *,
                      scale: float = 1.0, shared: Refolder | None = None,
                      progress: bool = False) -> list[np.ndarray]:
    """The RVM label image of every sample under the ISP setting of ``rvm``: equal to
    ``process(None, sample_images(...)[i].labels, params, output)`` (the tests check it), at
    the cost of re-folding only the fisheye pixels the RVM image shows.  ``rvm`` may be a
    function of the sample's position in ``samples`` giving its own setting's pixels
    (per-car values), called when its viewpoint's cube is at hand.

    Returns
    -------
    list of (H_o, W_o) uint8
        In ``samples``' order; ``VOID`` where the RVM image has no input.
    """
    if not samples:
        return []
    shared = shared if shared is not None else refolder(scene, samples, scale=scale)
    out: list[np.ndarray | None] = [None] * len(samples)
    bar = _bar(progress, len(samples), "samples")
    for idx, view_cam, _, atlas_l in _viewpoints(scene, samples, shared, scale, False):
        for i in idx:
            cam = sample_camera(scene, samples[i], scale=scale)
            px = rvm(i) if callable(rvm) else rvm
            ax, ay = refold_coords(shared.cover, cam.rotation.T @ view_cam.rotation, px.rays)
            at_pixels = np.full(px.pixels.size, L.VOID, np.uint8)
            at_pixels[px.in_field] = nearest_labels(atlas_l, ax, ay)
            out[i] = px.labels(at_pixels)
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    return [o for o in out if o is not None]


@dataclass(frozen=True)
class SampleSet:
    """Variation samples of one scene as a batch of fisheye images
    (:class:`rvmsim.pipeline.FisheyeSet`): what :func:`rvmsim.pipeline.make_evaluator` judges
    one ISP setting on.

    Parameters
    ----------
    scene : Scene
    samples : tuple of MountSample
    scale : float
        Fraction of the sensor rendered.
    shared : Refolder
        :func:`refolder` of a sample set holding ``samples`` (:meth:`of` makes it).
    """

    scene: Scene
    samples: tuple[MountSample, ...]
    scale: float
    shared: Refolder

    @classmethod
    def of(cls, scene: Scene, samples: Sequence[MountSample], *, scale: float = 1.0,
           shared: Refolder | None = None) -> SampleSet:
        """The set of ``samples`` (its :class:`Refolder` made here unless given)."""
        return cls(scene, tuple(samples), scale,
                   shared if shared is not None else refolder(scene, samples, scale=scale))

    @property
    def camera(self) -> FisheyeCamera:
        """The scene's camera at ``scale`` (the samples' lens and sensor size)."""
        cam = self.scene.fisheye_camera()
        return cam.scaled(self.scale) if self.scale != 1.0 else cam

    def __len__(self) -> int:
        return len(self.samples)

    def fisheye(self, indices: Sequence[int]) -> Iterator[FisheyeLabels]:
        """The samples' fisheye label images (:func:`sample_images`, no colour)."""
        yield from sample_images(self.scene, [self.samples[i] for i in indices],
                                 scale=self.scale, color=False, shared=self.shared)

    def rvm_labels(self, pixels: RvmPixels | Callable[[int], RvmPixels],
                   indices: Sequence[int]) -> Iterator[np.ndarray]:
        """The samples' RVM label images under ``pixels``' setting, or each under its own
        (``pixels(k)`` for ``indices[k]``; :func:`sample_rvm_labels`)."""
        yield from sample_rvm_labels(self.scene, [self.samples[i] for i in indices], pixels,
                                     scale=self.scale, shared=self.shared)
