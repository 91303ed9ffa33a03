"""Which fisheye pixels an RVM image shows under one ISP setting.

A setting's map is the same for every fisheye image of one camera model, so a batch of such
images (variation samples, cars off the line) needs only the labels of the fisheye pixels the
RVM image shows: :class:`RvmPixels` lists them once per setting, with their camera rays, and
a :class:`~rvmsim.pipeline.FisheyeSet` fills in each image's labels there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..isp import IspParams, OutputSpec, apply_map, build_map
from ..render import CameraRays

__all__ = ["RvmPixels", "rvm_pixels"]


@dataclass(frozen=True)
class RvmPixels:
    """Which fisheye pixel each RVM pixel shows under one ISP setting (the nearest sample of
    its map, as :func:`rvmsim.isp.process` takes labels).

    Attributes
    ----------
    source : (H_o, W_o) intp
        Flat fisheye index of each RVM pixel (−1: no input).
    pixels : (n,) intp
        The distinct fisheye pixels shown, ascending.
    inverse : (m,) intp
        Each used RVM pixel's entry in ``pixels`` (row-major over ``source >= 0``).
    rays : CameraRays
        The rays of ``pixels`` on the camera's lens.
    in_field : (n,) bool
        Which of ``pixels`` lie in the lens's field.
    """

    source: np.ndarray
    pixels: np.ndarray
    inverse: np.ndarray
    rays: CameraRays
    in_field: np.ndarray

    def labels(self, at_pixels: np.ndarray) -> np.ndarray:
        """The RVM label image from the labels at :attr:`pixels` (``VOID`` outside the field
        is the caller's): (H_o, W_o) uint8, ``VOID`` where the RVM image has no input."""
        out = np.full(self.source.shape, L.VOID, np.uint8)
        out[self.source >= 0] = at_pixels[self.inverse]
        return out


def rvm_pixels(camera: FisheyeCamera, params: IspParams, output: OutputSpec, *,
               camera_rays: CameraRays | None = None) -> RvmPixels:
    """:class:`RvmPixels` of ``params`` (for ``camera``'s sensor size) on ``camera``'s lens.

    Parameters
    ----------
    camera : FisheyeCamera
    params : IspParams
    output : OutputSpec
    camera_rays : CameraRays, optional
        ``CameraRays.of(camera)``: the rays of every in-field pixel, made once for many
        settings (per-car values).  The shown pixels' rays are then looked up in it rather
        than computed, and not made distinct (an RVM pixel per entry): cheaper per setting.

    Convention
    ----------
    Fisheye pixel ``k`` is row ``k // W``, column ``k % W``; the map samples it exactly as
    :func:`rvmsim.isp.apply_map` samples labels (nearest, pixel centres at integers).
    """
    w, h = camera.width, camera.height
    index = np.arange(1, w * h + 1, dtype=np.float32).reshape(h, w)  # exact below 2^24
    src = np.rint(apply_map(index, build_map(params, (w, h), output), labels=True))
    source = src.astype(np.intp) - 1
    if camera_rays is None:
        pixels, inverse = np.unique(source[source >= 0], return_inverse=True)
        rays = CameraRays.of(camera, pixels)
        return RvmPixels(source, pixels, inverse.ravel(), rays, rays.in_fov.ravel()[pixels])
    pixels = source[source >= 0]
    in_field = camera_rays.in_fov.ravel()[pixels]
    position = _ray_positions(camera_rays)[pixels[in_field]]
    rays = CameraRays(camera_rays.x[position], camera_rays.y[position], camera_rays.z[position],
                      pixels[in_field], camera_rays.in_fov)
    return RvmPixels(source, pixels, np.arange(pixels.size), rays, in_field)


def _ray_positions(camera_rays: CameraRays) -> np.ndarray:
    """Each fisheye pixel's entry in ``camera_rays`` (−1 outside the field)."""
    lut = np.full(camera_rays.in_fov.size, -1, np.intp)
    lut[camera_rays.index] = np.arange(camera_rays.index.size)
    return lut
