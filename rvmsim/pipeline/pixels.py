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

__all__ = ["RvmPixels", "rvm_pixels", "RayTable", "ray_table"]


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


@dataclass(frozen=True)
class RayTable:
    """What every setting's :class:`RvmPixels` on one camera shares (:func:`ray_table`):
    the rays of every in-field pixel, each pixel's entry among them (−1 outside the field)
    and the image of flat pixel indices + 1 (float32, exact below 2^24) the map samples."""

    rays: CameraRays
    entry: np.ndarray
    index_image: np.ndarray


def ray_table(camera: FisheyeCamera) -> RayTable:
    """The :class:`RayTable` of ``camera`` (made once for many settings: per-car values)."""
    rays = CameraRays.of(camera)
    entry = np.full(rays.in_fov.size, -1, np.intp)
    entry[rays.index] = np.arange(rays.index.size)
    w, h = camera.width, camera.height
    return RayTable(rays, entry, np.arange(1, w * h + 1, dtype=np.float32).reshape(h, w))


def rvm_pixels(camera: FisheyeCamera, params: IspParams, output: OutputSpec, *,
               table: RayTable | None = None) -> RvmPixels:
    """:class:`RvmPixels` of ``params`` (for ``camera``'s sensor size) on ``camera``'s lens.

    Parameters
    ----------
    camera : FisheyeCamera
    params : IspParams
    output : OutputSpec
    table : RayTable, optional
        :func:`ray_table` of ``camera``, made once for many settings (per-car values): the
        shown pixels' rays are then looked up rather than computed, and made distinct by
        marking them (linear time) rather than by sorting.

    Convention
    ----------
    Fisheye pixel ``k`` is row ``k // W``, column ``k % W``; the map samples it exactly as
    :func:`rvmsim.isp.apply_map` samples labels (nearest, pixel centres at integers).
    """
    w, h = camera.width, camera.height
    index = (table.index_image if table is not None else
             np.arange(1, w * h + 1, dtype=np.float32).reshape(h, w))  # exact below 2^24
    src = apply_map(index, build_map(params, (w, h), output), labels=True)
    source = src.astype(np.intp) - 1  # the values are whole numbers: exact
    shown = source[source >= 0]
    if table is None:
        pixels, inverse = np.unique(shown, return_inverse=True)
        rays = CameraRays.of(camera, pixels)
        return RvmPixels(source, pixels, inverse.ravel(), rays, rays.in_fov.ravel()[pixels])
    mark = np.zeros(w * h, bool)
    mark[shown] = True
    pixels = np.flatnonzero(mark)
    rank = np.cumsum(mark, dtype=np.intp) - 1
    in_field = table.rays.in_fov.ravel()[pixels]
    entry = table.entry[pixels[in_field]]
    r = table.rays
    rays = CameraRays(r.x[entry], r.y[entry], r.z[entry], pixels[in_field], r.in_fov)
    return RvmPixels(source, pixels, rank[shown], rays, in_field)
