"""The search space: coarse grids, narrowing, and the default space fitted to a camera."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.search import ParamRange, SearchSpace, default_space

from ..conftest import small_render


def test_param_grid_and_narrowing():
    r = ParamRange("zoom", init=0.7, low=0.25, high=1.45, step=0.3)
    np.testing.assert_allclose(r.grid(), [0.4, 0.7, 1.0])
    assert list(ParamRange("zoom", 0.3, 0.25, 1.45, 0.3).grid()) == pytest.approx([0.3, 0.6])
    assert len(ParamRange("fov", 180, 150, 210, 10, points=5).grid()) == 5
    space = SearchSpace((ParamRange("fov", 180, 150, 210, 20),
                         ParamRange("zoom", 0.7, 0.25, 1.45, 0.3),
                         ParamRange("adv_v_shift", 0.0, -0.8, 0.8, 0.4)))
    grid = list(space.grid())
    assert len(grid) == space.grid_size() == 27
    np.testing.assert_allclose(grid[0], [160, 0.4, -0.4])   # last parameter varies fastest
    np.testing.assert_allclose(grid[1], [160, 0.4, 0.0])
    lo, hi = space.narrowed(np.array([160.0, 1.3, 0.7]))
    np.testing.assert_allclose(lo, [150.0, 1.0, 0.3])       # clipped to the range below…
    np.testing.assert_allclose(hi, [180.0, 1.45, 0.8])      # … and above
    with pytest.raises(ValueError, match="zoom"):
        ParamRange("zoom", 0.1, 0.25, 1.45, 0.3)


def test_default_space_fits_the_camera():
    cam = small_render("b").camera
    space = default_space(cam)
    assert space.names == ("fov", "rad", "h_shift", "v_shift", "zoom", "adv_h_shift",
                           "adv_v_shift", "adv_h_scale", "adv_v_scale")
    rad = {r.name: r for r in space.ranges}["rad"]
    assert rad.init == pytest.approx(cam.fx * np.pi / 2)
    h = {r.name: r for r in space.ranges}["h_shift"]
    assert h.init == pytest.approx(cam.cx - (cam.width - 1) / 2)
    assert space.grid_size() == 3 ** 9
