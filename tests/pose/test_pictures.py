"""rvmsim.pose.pictures: the pose search's pictures."""

from __future__ import annotations

import numpy as np

from rvmsim.pose import blend, landmark_picture
from rvmsim.testing.captures import perturbed_validation


def test_blend_and_landmark_picture():
    a = np.full((4, 4, 3), 10, np.uint8)
    b = np.full((4, 4, 3), 251, np.uint8)
    assert (blend(a, b) == 130).all()
    res, _ = perturbed_validation()
    cap = np.zeros((480, 640, 3), np.uint8)
    pic = landmark_picture(cap, res.landmarks)
    m = next(m for m in res.landmarks if m.inlier)
    u, v = (int(round(x)) for x in m.corrected_px)
    assert tuple(pic[v, u]) == (0, 220, 255)  # the corrected reprojection: a cyan dot
    assert not cap.any()  # the capture is not drawn on
