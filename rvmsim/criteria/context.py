"""What an EC may know besides the RVM label pixels: the scene and the candidate's ISP map.

Most ECs judge the RVM label image alone.  Some need more: the full silhouette of a test
object, also where it is hidden (the scene's geometry and the camera), its size on the
driver's display (a display model), or how much the ISP magnifies the fisheye image there
(the candidate's map).  A label source offers these as

- ``source.context``: a :class:`SceneContext` (per scene: the scene, the fisheye camera the
  label image was rendered with, that label image, and a per-scene cache for work done once
  per scene, :meth:`SceneContext.shared`), or ``None`` when the caller knows no scene;
- ``source.isp``: an :class:`IspView` (per candidate: the ISP parameters, the fisheye and RVM
  image sizes, and exact point mappings between them), or ``None``.

An EC that needs either returns ``Measurement(None)`` (cannot be measured) when it is
``None``, as it does for an empty image.

Conventions: pixel centres at integer coordinates in both images (OpenCV); fisheye = the ISP's
input image, RVM = its output image.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from ..camera import FisheyeCamera
from ..isp import IspParams, OutputSpec, input_to_output, roi_outline
from ..scene import Display, Scene

__all__ = ["SceneContext", "IspView", "scene_context"]

T = TypeVar("T")


class SceneContext:
    """One scene as the ECs see it: its description, camera and fisheye label image.

    Parameters
    ----------
    scene : Scene
        The vehicle and test site (object positions and sizes, the optional ``display``).
    camera : FisheyeCamera
        The camera the fisheye label image was rendered with (its size: the ISP's input).
    fisheye_labels : (H_i, W_i) uint8
        The rendered fisheye label image (read-only).

    Notes
    -----
    Picklable (tuning sends it to worker processes with the evaluator); the per-scene cache
    travels with it.
    """

    def __init__(self, scene: Scene, camera: FisheyeCamera, fisheye_labels: np.ndarray):
        labels = np.asarray(fisheye_labels)
        if labels.shape != (camera.height, camera.width):
            raise ValueError(f"the fisheye labels are {labels.shape[1]}x{labels.shape[0]} px but "
                             f"the camera is {camera.width}x{camera.height}")
        self.scene = scene
        self.camera = camera
        self.fisheye_labels = labels
        self._shared: dict[Hashable, Any] = {}  # each value of its caller's own type

    def shared(self, key: Hashable, compute: Callable[[], T]) -> T:
        """``compute()``, once per scene (e.g. an object's silhouette in the fisheye image);
        ``key`` names the work and its options."""
        try:
            return self._shared[key]
        except KeyError:
            out = self._shared[key] = compute()
            return out

    @property
    def sensor_scale(self) -> float:
        """Rendered fisheye px per sensor px (< 1 for a render at a fraction of the sensor):
        per-pixel figures of the real camera divide by it."""
        return self.camera.width / self.scene.camera.image_size[0]

    def display(self, fallback: Display | None = None) -> Display:
        """The display: the scene's ``display`` section, else ``fallback`` (the criteria
        file's), else the defaults (:mod:`rvmsim.scene.fmvss111`)."""
        return self.scene.display or fallback or Display()


def scene_context(scene: Scene | None, camera: FisheyeCamera | None,
                  fisheye_labels: np.ndarray) -> SceneContext | None:
    """A :class:`SceneContext`, or None without a scene.  ``camera`` defaults to the scene's,
    scaled to the label image's size (a render at a fraction of the sensor)."""
    if scene is None:
        return None
    if camera is None:
        camera = scene.fisheye_camera()
        h, w = np.asarray(fisheye_labels).shape[:2]
        if (w, h) != (camera.width, camera.height):
            camera = camera.scaled(w / camera.width)
    return SceneContext(scene, camera, fisheye_labels)


@dataclass(frozen=True)
class IspView:
    """One candidate's ISP map, as exact point mappings (cheap: a few points per EC).

    Parameters
    ----------
    params : IspParams
        The parameters as applied to the fisheye image (for its size).
    input_size : (int, int)
        (W_i, H_i) of the fisheye image, px.
    output : OutputSpec
        The RVM image (size, mirroring).
    """

    params: IspParams
    input_size: tuple[int, int]
    output: OutputSpec

    def to_output(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Fisheye px (N, 2) → RVM px (N, 2) float64, and (N,) bool: the point is in front of
        the virtual image plane (:func:`rvmsim.isp.input_to_output`)."""
        return input_to_output(self.params, np.asarray(points, np.float64).reshape(-1, 2),
                               self.input_size, self.output)

    def footprint(self, samples_per_side: int = 64) -> np.ndarray:
        """The RVM image's border in fisheye px: a closed polygon (N, 2) float64
        (:func:`rvmsim.isp.roi_outline`, output pixel centres 0 … W − 1, 0 … H − 1)."""
        return roi_outline(self.params, self.input_size, self.output,
                           samples_per_side=samples_per_side)

    def output_jacobian(self, points: np.ndarray, step_px: float = 0.5) -> np.ndarray:
        """d(RVM px)/d(fisheye px) at fisheye points (N, 2): (N, 2, 2) float64, row i =
        output coordinate i, column j = input coordinate j (central differences of the
        exact inverse map, ±``step_px``; error O(step²), ~1e-6 relative here)."""
        pts = np.asarray(points, np.float64).reshape(-1, 2)
        d = np.array([[step_px, 0.0], [0.0, step_px]])
        probes = np.concatenate([pts + d[0], pts - d[0], pts + d[1], pts - d[1]])
        uv, _ = self.to_output(probes)
        n = len(pts)
        du = (uv[:n] - uv[n : 2 * n]) / (2 * step_px)  # d(out)/d(u_in)
        dv = (uv[2 * n : 3 * n] - uv[3 * n :]) / (2 * step_px)  # d(out)/d(v_in)
        return np.stack([du, dv], axis=2)

    def magnification(self, points: np.ndarray) -> np.ndarray:
        """Local magnification at fisheye points (N, 2): RVM px per fisheye px in the most
        magnified direction (the larger singular value of :meth:`output_jacobian`), (N,)."""
        jac = self.output_jacobian(points)
        if len(jac) == 0:
            return np.zeros(0)
        return np.linalg.svd(jac, compute_uv=False)[:, 0]
