"""Fisheye camera model: the rear-view camera ("P camera" of the paper, section III-B).

Conventions
-----------
Frames (scene and camera) and the mount angles: see :mod:`rvmsim.camera.mount`.

Pixels: OpenCV's convention, pixel centres at integer coordinates, (u, v) = (column, row),
origin at the centre of the top-left pixel.

Lens: a radial model (:mod:`rvmsim.camera.lens`) maps the incidence angle θ (radians, from
the optical axis) of a ray with azimuth φ to the distorted angle θ_d, and

    u   = fx · (θ_d·cos φ + skew · θ_d·sin φ) + cx
    v   = fy ·  θ_d·sin φ + cy

The camera's ``lens_model`` names the model (no coefficient sniffing): Kannala-Brandt with
``k`` = (k1..k4) exactly as ``cv2.fisheye`` defines it (:mod:`rvmsim.camera.kannala_brandt`),
or the equidistance lens r = f·θ (:mod:`rvmsim.camera.equidistance`, the paper's equation (3)).  Unlike
``cv2.fisheye.projectPoints`` (which uses θ = atan(r/z) and so breaks down behind the
camera's principal plane), θ = atan2(√(x²+y²), z) here, so rays beyond 90° — which a 190°
lens sees — project correctly.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import cv2
import numpy as np

from . import equidistance, kannala_brandt  # noqa: F401 - they register their models
from .lens import LensModel, make_lens

__all__ = ["FisheyeCamera"]


#: :meth:`FisheyeCamera.image_rays` of the last few intrinsics (key → (rays, in_fov)).
_IMAGE_RAYS: dict[tuple[object, ...], tuple[np.ndarray, np.ndarray]] = {}
_IMAGE_RAYS_KEPT = 2

@dataclass(frozen=True)
class FisheyeCamera:
    """A calibrated fisheye camera at a pose in the scene.

    Parameters
    ----------
    width, height : int
        Image size in px.
    fx, fy : float
        Focal lengths in px/rad (the Kannala-Brandt / equidistance scale; fx ≠ fy allowed).
    cx, cy : float
        Principal point in px (pixel-centre convention).
    k : (4,) tuple of float
        Kannala-Brandt coefficients k1..k4; all zero for an equidistance lens.
    skew : float
        cv2.fisheye's alpha (K[0, 1] = fx · skew); usually 0.
    fov_deg : float
        Full field of view of the lens in degrees; rays beyond fov_deg / 2 from the optical axis
        never reach the sensor (those pixels are dark and labelled void).
    rotation : (3, 3) float
        Camera-to-scene rotation (see :func:`~rvmsim.camera.rotation_from_ypr`).
    position : (3,) float
        Optical centre in scene coordinates, metres.
    lens_model : str
        The lens model's name (:data:`rvmsim.camera.LENS_MODELS`), built with ``k``
        (:func:`rvmsim.camera.make_lens`).  Default ``kannala_brandt``, cv2.fisheye's model
        that ``k`` describes; a scene's ``camera.lens.model`` sets it (its default is
        ``equidistance``, the paper's).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    k: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    skew: float = 0.0
    fov_deg: float = 190.0
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    lens_model: str = "kannala_brandt"

    def __post_init__(self) -> None:
        if self.width <= 0 or self.height <= 0:
            raise ValueError(f"image size must be positive, got {self.width}x{self.height}")
        if self.fx <= 0 or self.fy <= 0:
            raise ValueError(f"focal lengths must be positive, got fx={self.fx}, fy={self.fy}")
        if not 0 < self.fov_deg <= 360:
            raise ValueError(f"fov_deg must be in (0, 360], got {self.fov_deg}")
        rot = np.asarray(self.rotation, dtype=np.float64)
        pos = np.asarray(self.position, dtype=np.float64)
        if rot.shape != (3, 3) or not np.allclose(rot @ rot.T, np.eye(3), atol=1e-9):
            raise ValueError("rotation must be a (3, 3) orthonormal matrix")
        if pos.shape != (3,):
            raise ValueError("position must have shape (3,)")
        rot.setflags(write=False)
        pos.setflags(write=False)
        object.__setattr__(self, "rotation", rot)
        object.__setattr__(self, "position", pos)
        object.__setattr__(self, "k", tuple(float(x) for x in self.k))
        make_lens(self.lens_model, self.k)  # an unknown model or unfit k: ValueError here
        # The distortion polynomial must be one-to-one over the lens's field.
        if not self.lens.is_monotonic(self.theta_max):
            raise ValueError(
                "lens distortion k1..k4 is not monotonic up to fov_deg/2: the image would fold"
            )

    # ------------------------------------------------------------------ properties
    @property
    def lens(self) -> LensModel:
        """The lens: the model :attr:`lens_model` names, with coefficients ``k``."""
        return make_lens(self.lens_model, self.k)

    @property
    def theta_max(self) -> float:
        """Half the lens's field of view, radians."""
        return float(np.radians(self.fov_deg) / 2.0)

    @property
    def K(self) -> np.ndarray:
        """The 3×3 camera matrix in cv2.fisheye's layout."""
        return np.array(
            [[self.fx, self.fx * self.skew, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]]
        )

    @property
    def D(self) -> np.ndarray:
        """The (4, 1) distortion vector in cv2.fisheye's layout."""
        return np.asarray(self.k, dtype=np.float64).reshape(4, 1)

    @property
    def rvec_tvec(self) -> tuple[np.ndarray, np.ndarray]:
        """Scene-to-camera pose as OpenCV (rvec, tvec), for cv2.fisheye.projectPoints."""

        r_sc = self.rotation.T
        rvec, _ = cv2.Rodrigues(r_sc)
        tvec = -r_sc @ self.position
        return rvec.reshape(3, 1), tvec.reshape(3, 1)

    def scaled(self, factor: float) -> FisheyeCamera:
        """The same lens on a sensor resampled by ``factor`` (e.g. 0.25 for a quick preview).

        Focal lengths scale with the factor; the principal point scales about the pixel
        *edges* (``(c + 0.5) · factor − 0.5``), so the image content stays in place.
        """
        w = max(1, int(round(self.width * factor)))
        h = max(1, int(round(self.height * factor)))
        sx, sy = w / self.width, h / self.height
        return dataclasses.replace(self, width=w, height=h, fx=self.fx * sx, fy=self.fy * sy,
                                   cx=(self.cx + 0.5) * sx - 0.5, cy=(self.cy + 0.5) * sy - 0.5,
                                   skew=self.skew * sy / sx)

    # ------------------------------------------------------------------ projection
    def scene_to_camera(self, points: np.ndarray) -> np.ndarray:
        """Scene points → camera-frame points.

        Parameters
        ----------
        points : (N, 3) float
            Points in the scene frame, metres (any shape with a last axis of 3; flattened).

        Returns
        -------
        (N, 3) float64
            The points in the camera frame, metres, relative to the optical centre.

        Convention
        ----------
        Frames as in :mod:`rvmsim.camera.mount`: ``p_cam = R_cam_to_sceneᵀ · (p − position)``.
        """
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        return (pts - self.position) @ self.rotation

    def project_rays(self, rays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project camera-frame directions to pixels.

        Parameters
        ----------
        rays : (N, 3) float
            Directions (or points) in the camera frame; need not be unit length.

        Returns
        -------
        uv : (N, 2) float64
            Pixel coordinates (u = column, v = row), px.
        in_fov : (N,) bool
            True where the ray lies within the lens's field of view (θ ≤ fov_deg / 2).

        Convention
        ----------
        Camera frame as in :mod:`rvmsim.camera.mount`; pixel centres at integer coordinates,
        (0, 0) the centre of the top-left pixel.  θ = atan2(√(x² + y²), z), so rays beyond
        90° from the axis project too.
        """
        r = np.asarray(rays, dtype=np.float64).reshape(-1, 3)
        rho = np.hypot(r[:, 0], r[:, 1])
        theta = np.arctan2(rho, r[:, 2])
        theta_d = self.lens.distort(theta)
        safe = np.where(rho > 0, rho, 1.0)
        xd = np.where(rho > 0, theta_d * r[:, 0] / safe, 0.0)
        yd = np.where(rho > 0, theta_d * r[:, 1] / safe, 0.0)
        u = self.fx * (xd + self.skew * yd) + self.cx
        v = self.fy * yd + self.cy
        return np.stack([u, v], axis=1), theta <= self.theta_max

    def project(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Project scene points (N, 3), metres, to pixels (u, v) px and the in-field mask.

        Convention
        ----------
        Scene frame in, pixel centres at integer coordinates out; see
        :meth:`scene_to_camera` and :meth:`project_rays`.
        """
        return self.project_rays(self.scene_to_camera(points))

    def pixel_rays(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Back-project pixels to unit rays in the camera frame.

        Parameters
        ----------
        uv : (..., 2) float
            Pixel coordinates (u = column, v = row), px.

        Returns
        -------
        rays : (..., 3) float64
            Unit directions in the camera frame.
        in_fov : (...) bool
            True where the pixel lies inside the lens's image circle (θ ≤ fov/2).

        Convention
        ----------
        Pixel centres at integer coordinates, (0, 0) the centre of the top-left pixel; camera
        frame as in :mod:`rvmsim.camera.mount`.  The inverse of :meth:`project_rays`.
        """
        uv = np.asarray(uv, dtype=np.float64)
        yd = (uv[..., 1] - self.cy) / self.fy
        xd = (uv[..., 0] - self.cx) / self.fx - self.skew * yd
        theta_d = np.hypot(xd, yd)
        theta = self.lens.undistort(theta_d, theta_max=self.theta_max)
        in_fov = theta <= self.theta_max
        safe = np.where(theta_d > 0, theta_d, 1.0)
        s = np.sin(theta)
        x = np.where(theta_d > 0, s * xd / safe, 0.0)
        y = np.where(theta_d > 0, s * yd / safe, 0.0)
        rays = np.stack([x, y, np.cos(theta)], axis=-1)
        return rays, in_fov

    def image_rays(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit rays (H, W, 3), camera frame, for every pixel centre, and the (H, W) in-field
        mask.

        Convention
        ----------
        ``rays[v, u]`` is the ray of the pixel centre (u, v) (integer px); see
        :meth:`pixel_rays`.  The rays depend on the intrinsics and lens only, not on the
        mount: the last few sets are kept (read-only arrays, shared) for cameras that differ
        only in their mount, such as a sweep's design points and variation samples.
        """
        key = (self.width, self.height, self.fx, self.fy, self.cx, self.cy, tuple(self.k),
               self.skew, self.fov_deg)
        found = _IMAGE_RAYS.get(key)
        if found is None:
            u, v = np.meshgrid(np.arange(self.width), np.arange(self.height))
            found = self.pixel_rays(np.stack([u, v], axis=-1).astype(np.float64))
            for a in found:
                a.setflags(write=False)  # shared by every camera with these intrinsics
            if len(_IMAGE_RAYS) >= _IMAGE_RAYS_KEPT:
                _IMAGE_RAYS.pop(next(iter(_IMAGE_RAYS)))
            _IMAGE_RAYS[key] = found
        return found
