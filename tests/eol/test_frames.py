"""Frames of a scene from any pose (rvmsim.eol.frames): only the pixels an RVM image shows."""

from __future__ import annotations

import numpy as np

from rvmsim import labels as L
from rvmsim.compensation import Deviation
from rvmsim.eol import car_camera
from rvmsim.eol.frames import PoseRenderer, restricted_layout
from rvmsim.pipeline import rvm_pixels

from rvmsim.testing.stations import platform, station_scene


def test_the_shown_pixels_alone_render_as_in_the_whole_frame():
    sc = station_scene()
    cam = sc.fisheye_camera()
    renderer = PoseRenderer(sc, cam)
    pose = car_camera(sc, Deviation(2, -3, 4, 0.5, -0.4, 0.3))
    params, output = platform()
    shown = np.zeros(cam.width * cam.height, bool)
    shown[rvm_pixels(pose, params, output).pixels] = True
    shown = shown.reshape(cam.height, cam.width)
    part = restricted_layout(renderer.layout, shown)
    whole_area = sum(c.width * c.height for c in renderer.layout.crops)
    assert sum(c.width * c.height for c in part.crops) < 0.7 * whole_area
    assert part.face_size == renderer.layout.face_size
    full = renderer.labels(pose)
    some = renderer.labels(pose, shown)
    # The same face pixels: equal but for pixels on an edge that the shifted projection
    # window rasterises the other way (2 of 505,000 at 1280 × 960).
    assert (full[shown] != some[shown]).mean() < 1e-4
    assert np.all(some[~shown] == L.VOID)
    # Keeping every pixel gives the layout back.
    same = restricted_layout(renderer.layout, np.ones_like(shown))
    assert [(c.face, c.width, c.height) for c in same.crops] == [
        (c.face, c.width, c.height) for c in renderer.layout.crops]
    assert np.array_equal(same.atlas_x, renderer.layout.atlas_x)
