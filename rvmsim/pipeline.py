"""Scene → RVM image in one call (render once, then the ISP), for the CLI and for scripts."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .isp import IspParams, OutputSpec, process
from .render import FisheyeImages, render_fisheye
from .scene import Scene

__all__ = ["RvmFrame", "render_rvm"]


@dataclass(frozen=True)
class RvmFrame:
    """A rendered fisheye frame and its RVM image under one ISP parameter set.

    ``params`` are the parameters as applied to ``fisheye`` (RAD and shifts scaled when the
    fisheye was rendered at a fraction of the sensor).
    """

    fisheye: FisheyeImages
    params: IspParams
    output: OutputSpec
    color: np.ndarray
    labels: np.ndarray


def render_rvm(scene: Scene, params: IspParams, output: OutputSpec = OutputSpec(), *,
               scale: float = 1.0, progress: bool = False) -> RvmFrame:
    """Render ``scene`` (at ``scale`` of its sensor size) and run the ISP on it.

    Parameters
    ----------
    scene : Scene
    params : IspParams
        ISP parameters for the full-size sensor.
    output : OutputSpec
        RVM image size and mirroring.
    scale : float
        Fraction of the sensor to render (RAD and the shifts follow, the view stays).
    progress : bool
        Progress bar while rendering.
    """
    cam = scene.fisheye_camera()
    if scale != 1.0:
        cam = cam.scaled(scale)
        params = params.for_input_scale(cam.width / scene.camera.image_size[0])
    images = render_fisheye(scene, camera=cam, progress=progress)
    color, labels = process(images.color, images.labels, params, output)
    return RvmFrame(fisheye=images, params=params, output=output, color=color, labels=labels)
