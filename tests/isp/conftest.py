"""ISP-test data: an input size and parameter sets over Table 2's ranges."""

from __future__ import annotations

from rvmsim.isp import IspParams

#: (width, height) of the fisheye input the map tests use, px.
INPUT = (1280, 960)

PARAM_SETS = [
    IspParams(),
    IspParams(fov=190, rad=600, h_shift=12, v_shift=-30, zoom=0.8, adv_h_shift=0.1,
              adv_v_shift=0.35, adv_h_scale=1.2, adv_v_scale=0.9),
    IspParams(fov=170, rad=700, h_pan=25, v_pan=60, tilt=-12, zoom=1.4, theta=20, phi=-35),
    IspParams(fov=200, rad=640, h_pan=40, v_pan=-120, tilt=170, zoom=2.5, theta=5, phi=150),
]
