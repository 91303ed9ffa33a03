"""Views of the bundled vehicles in which every measured object is visible, and projections
of scene points into them: the independent geometry the EC measurements are checked against."""

from __future__ import annotations

import cv2
import numpy as np

from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map, input_to_output

from ..conftest import sensor_render

#: RVM size for the analytic comparisons: no finer than the fisheye where the view is widest,
#: so one RVM pixel never magnifies more than one fisheye pixel (nearest sampling of a
#: magnified image moves borders by half a fisheye pixel × the magnification).
OUT = OutputSpec(400, 225, mirror=True)
#: A view of each vehicle in which every measured object is inside the image, not occluded.
#: Found for the half-size sensors; the tests use the full 1280×960 fisheye (RAD and shifts
#: doubled), so that the fisheye is at least as sharp as the RVM image.
VIEWS = {
    "a": IspParams(fov=180, rad=300, v_shift=-27, zoom=0.3, adv_v_shift=0.39, adv_h_scale=0.9,
                   adv_v_scale=0.92).for_input_scale(2.0),
    "b": IspParams(fov=180, rad=303, v_shift=35, zoom=0.36, adv_v_shift=0.01, adv_h_scale=0.89,
                   adv_v_scale=1.06).for_input_scale(2.0),
}


def project(letter: str, params: IspParams, pts: np.ndarray) -> np.ndarray:
    """3D scene points → RVM px: cv2.fisheye.projectPoints, then the inverse ISP."""
    cam = sensor_render(letter).camera
    rvec, tvec = cam.rvec_tvec
    uv, _ = cv2.fisheye.projectPoints(np.asarray(pts, float).reshape(-1, 1, 3), rvec, tvec,
                                      cam.K, cam.D, alpha=cam.skew)
    out, ok = input_to_output(params, uv.reshape(-1, 2), (cam.width, cam.height), OUT)
    assert ok.all()
    return out


def rvm(letter: str):
    img = sensor_render(letter)
    m = build_map(VIEWS[letter], (img.camera.width, img.camera.height), OUT)
    return apply_map(img.labels, m)


def ring(centre, radius, height, az0, az1, n=400):
    az = np.radians(np.linspace(az0, az1, n))
    return np.stack([centre[0] + radius * np.sin(az), np.full(n, -height),
                     centre[1] + radius * np.cos(az)], 1)


def polygon_area(uv: np.ndarray) -> float:
    x, y = uv[:, 0], uv[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


