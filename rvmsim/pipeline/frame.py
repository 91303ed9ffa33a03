"""The full evaluation path: ISP parameters → RVM colour and label images → ECs → annotated
image.

:func:`evaluate_params` makes one candidate's whole frame, for rendered fisheye images:
tuning's results, the review report, ``rvmsim evaluate`` and ``process``, validation, the
console and the sweep all call it.  :func:`evaluate_rvm_labels` is its label-only part: the
reference every fast path of :func:`rvmsim.pipeline.make_evaluator` is tested against.
:func:`render_rvm` renders a scene first (at a fraction of its sensor, if asked).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..criteria import (Criteria, EcFailedError, EcResult, IspView, SceneContext,
                        default_criteria, evaluate, scene_context)
from ..criteria import annotate as annotate_ecs
from ..isp import IspParams, OutputSpec, process
from ..render import FisheyeImages, cached_render
from ..scene import Scene

__all__ = ["RvmFrame", "evaluate_params", "evaluate_rvm_labels", "rvm_color", "render_rvm"]


@dataclass(frozen=True)
class RvmFrame:
    """A rendered fisheye frame, its RVM images under one ISP parameter set, and their ECs.

    ``params`` are the parameters as applied to ``fisheye`` (RAD and shifts scaled when the
    fisheye was rendered at a fraction of the sensor).  ``color`` is (H, W, 3) uint8 and
    ``labels`` (H, W) uint8 at ``output``'s size; ``ec`` the ECs measured on ``labels``;
    ``annotated`` the measurements drawn on ``color`` with a results panel (None when not
    asked for).
    """

    fisheye: FisheyeImages
    params: IspParams
    output: OutputSpec
    color: np.ndarray
    labels: np.ndarray
    ec: EcResult
    annotated: np.ndarray | None = None


def evaluate_params(images: FisheyeImages, params: IspParams, output: OutputSpec,
                    criteria: Criteria | None = None, *, annotate: bool = True) -> RvmFrame:
    """Run the ISP on rendered fisheye images and evaluate the RVM image.

    Parameters
    ----------
    images : FisheyeImages
        Rendered fisheye colour and label images (``images.scene``, when set, is the scene
        that ECs needing its geometry or display read).
    params : IspParams
        ISP parameters for ``images``' size.
    output : OutputSpec
        RVM image size (px) and mirroring.
    criteria : Criteria, optional
        Default: the paper's (:func:`rvmsim.criteria.default_criteria`).
    annotate : bool
        Also draw the ECs (:func:`rvmsim.criteria.annotate`).

    Returns
    -------
    RvmFrame
    """
    criteria = criteria if criteria is not None else default_criteria()
    color, labels = process(images.color, images.labels, params, output)
    assert color is not None and labels is not None  # process returns what it is given
    ec = evaluate_rvm_labels(labels, images.labels, params, output, criteria,
                             context=_context(images))
    try:
        drawn = annotate_ecs(color, labels, ec) if annotate else None
    except EcFailedError as err:  # name the scene too
        h, w = labels.shape
        raise err.on(f"the {w}x{h} RVM image of {images.scene.source}" if images.scene
                     else err.image) from None
    return RvmFrame(fisheye=images, params=params, output=output, color=color, labels=labels,
                    ec=ec, annotated=drawn)


def _context(images: FisheyeImages) -> SceneContext | None:
    return scene_context(images.scene, images.camera, images.labels)


def evaluate_rvm_labels(rvm_labels: np.ndarray, fisheye_labels: np.ndarray, params: IspParams,
                        output: OutputSpec, criteria: Criteria, *,
                        context: SceneContext | None) -> EcResult:
    """The ECs of one RVM label image made by ``params`` from ``fisheye_labels``.

    Parameters
    ----------
    rvm_labels : (H_o, W_o) uint8
        ``process(None, fisheye_labels, params, output)``'s label image.
    fisheye_labels : (H_i, W_i) uint8
        The ISP's input label image (its size is the map's input size).
    params : IspParams
        For ``fisheye_labels``' size.
    output : OutputSpec
    criteria : Criteria
    context : SceneContext or None
        The scene shown (:func:`rvmsim.criteria.scene_context`), for ECs that read it
        (1-5, 1-6, 6-1); None when no scene is known.
    """
    isp = IspView(params, (fisheye_labels.shape[1], fisheye_labels.shape[0]), output)
    return evaluate(rvm_labels, criteria, context=context, isp=isp)


def rvm_color(images: FisheyeImages, params: IspParams, output: OutputSpec) -> np.ndarray:
    """Only the RVM colour image (no labels, no ECs): (H, W, 3) uint8 at ``output``'s size,
    e.g. the same view at a display's size or a thumbnail of another candidate."""
    color, _ = process(images.color, None, params, output)
    assert color is not None
    return color


def render_rvm(scene: Scene, params: IspParams, output: OutputSpec = OutputSpec(), *,
               criteria: Criteria | None = None, scale: float = 1.0, annotate: bool = False,
               progress: bool = False) -> RvmFrame:
    """Render ``scene`` (at ``scale`` of its sensor size) and evaluate ``params`` on it
    (:func:`evaluate_params`).

    The fisheye images come from the render cache (:func:`rvmsim.render.cached_render`:
    rendered and stored on a miss), the same images ``tune``, the console and the
    sign-off read, so a params file measures the same whichever command measures it.

    Parameters
    ----------
    scene : Scene
    params : IspParams
        ISP parameters for the full-size sensor.
    output : OutputSpec
        RVM image size and mirroring.
    criteria : Criteria, optional
        Default: the paper's.
    scale : float
        Fraction of the sensor to render (RAD and the shifts follow, the view stays).
    annotate : bool
        Also draw the ECs.
    progress : bool
        Progress bar while rendering.
    """
    cam = scene.fisheye_camera()
    if scale != 1.0:
        cam = cam.scaled(scale)
        params = params.for_input_scale(cam.width / scene.camera.image_size[0])
    images, _ = cached_render(scene, scale=scale, progress=progress)
    return evaluate_params(images, params, output, criteria, annotate=annotate)
