"""Landmarks: the scene's checker corners and which of them the synthetic frame shows usably.

Every inner checker corner of the scene (the calibration board's, the ground patterns') is
predicted from the scene (:func:`rvmsim.scene.checker_corners`) and kept if the rendered label
image shows it unoccluded, well inside the lens's field, and large enough in the image.
Only saddle points (X corners) are landmarks: they refine without bias, plain corners
(guideline ends, outer mat corners) do not.  :mod:`.matching` finds them in a capture.

Convention
----------
Pixels are (u, v) = (column, row) with pixel centres at integer coordinates, as in
:mod:`rvmsim.camera`; an image is indexed ``[v, u]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera
from ..errors import RvmsimError
from ..render import FisheyeImages
from ..scene import CheckerCorner, Scene, checker_corners
from .projection import project

__all__ = [
    "MIN_SPACING_PX",
    "VisibleLandmarks",
    "visible_landmarks",
    "spacing_px",
    "usable_corners",
]

#: Corners whose neighbours are closer than this in the image are too small to use, px.
MIN_SPACING_PX = 8.0


@dataclass(frozen=True)
class VisibleLandmarks:
    """The scene's checker corners and which of them the synthetic frame shows usably.

    Attributes
    ----------
    corners : tuple of CheckerCorner
        Every checker corner of the scene.
    points : (N, 3) float
        Their scene points, m.
    predicted_px : (N, 2) float
        Their pixels with the scene's mount pose, px.
    usable : (N,) bool
        Seen unoccluded, inside the field and far enough apart (:func:`usable_corners`).
    """

    corners: tuple[CheckerCorner, ...]
    points: np.ndarray
    predicted_px: np.ndarray
    usable: np.ndarray

    @property
    def n_usable(self) -> int:
        return int(self.usable.sum())


def visible_landmarks(scene: Scene, synthetic: FisheyeImages,
                      min_landmarks: int) -> VisibleLandmarks:
    """The scene's checker corners, predicted with its own pose, and which are usable.

    Raises
    ------
    RvmsimError
        The scene has no checker corners, or fewer than ``min_landmarks`` are usable.
    """
    cam = synthetic.camera
    corners = checker_corners(scene)
    if not corners:
        raise RvmsimError(f"{scene.source}: the scene has no checker landmarks (enable "
                          "test_site.board or add test_site.ground_patterns)")
    pts = np.array([c.point for c in corners])
    uv = project(cam, cam.position, cam.rotation, pts)
    spacing = spacing_px(cam, cam.position, cam.rotation, corners)
    usable = usable_corners(cam, corners, synthetic.labels, uv, spacing)
    n_usable = int(usable.sum())
    if n_usable < min_landmarks:
        raise RvmsimError(f"{scene.source}: only {n_usable} checker corners are visible in "
                          f"the synthetic frame (need {min_landmarks})")
    return VisibleLandmarks(tuple(corners), pts, uv, usable)


def spacing_px(camera: FisheyeCamera, position: np.ndarray, rotation: np.ndarray,
               corners: list[CheckerCorner] | tuple[CheckerCorner, ...]) -> np.ndarray:
    """Image distance from each corner to its nearest checker neighbour, px.

    Parameters
    ----------
    camera : FisheyeCamera
        Lens and intrinsics.
    position : (3,) float
        Optical centre, m.
    rotation : (3, 3) float
        Camera-to-scene rotation.
    corners : sequence of CheckerCorner

    Returns
    -------
    (N,) float
        Smallest of the distances to the four neighbours one square away, px.
    """
    p = np.array([c.point for c in corners])
    a = np.array([c.axis_a for c in corners]) * np.array([[c.square_size] for c in corners])
    b = np.array([c.axis_b for c in corners]) * np.array([[c.square_size] for c in corners])
    uv = project(camera, position, rotation, p)
    d = [np.linalg.norm(project(camera, position, rotation, p + s) - uv, axis=1)
         for s in (a, -a, b, -b)]
    return np.asarray(np.min(d, axis=0))


def usable_corners(camera: FisheyeCamera,
                   corners: list[CheckerCorner] | tuple[CheckerCorner, ...],
                   labels: np.ndarray, uv: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """Corners seen unoccluded and far enough from the image border and the field's edge.

    A corner is usable when its neighbours are ≥ :data:`MIN_SPACING_PX` away, it lies ≥ 3°
    inside the lens's field, and ≥ 97 % of the label window around it (half-size
    0.45 × spacing + 2 px, clipped to 6..26 px) is the corner's own label.

    Parameters
    ----------
    camera : FisheyeCamera
        The pose the label image was rendered with.
    corners : sequence of CheckerCorner
    labels : (H, W) uint8
        The rendered label image.
    uv : (N, 2) float
        The corners' pixels in ``labels``, px.
    spacing : (N,) float
        :func:`spacing_px` at that pose, px.

    Returns
    -------
    (N,) bool
    """
    h, w = labels.shape
    p = np.array([c.point for c in corners])
    cam_pts = camera.scene_to_camera(p)
    theta = np.degrees(np.arctan2(np.hypot(cam_pts[:, 0], cam_pts[:, 1]), cam_pts[:, 2]))
    ok = (spacing >= MIN_SPACING_PX) & (theta <= camera.fov_deg / 2 - 3.0)
    half = np.clip(np.round(0.45 * spacing), 4, 24).astype(int)
    for n, c in enumerate(corners):
        if not ok[n]:
            continue
        x, y = int(round(uv[n, 0])), int(round(uv[n, 1]))
        r = half[n] + 2
        if x - r < 0 or y - r < 0 or x + r >= w or y + r >= h:
            ok[n] = False
            continue
        win = labels[y - r:y + r + 1, x - r:x + r + 1]
        ok[n] = float(np.mean(win == c.label)) >= 0.97
    return np.asarray(ok)
