"""Mount angles: the signs of yaw, pitch and roll in the scene frame."""

from __future__ import annotations

import numpy as np

from rvmsim.camera import FisheyeCamera, rotation_from_ypr


def test_mount_angle_conventions():
    z = np.array([0.0, 0.0, 1.0])
    down = rotation_from_ypr(0, 30, 0) @ z
    assert down[1] > 0 and np.isclose(np.degrees(np.arcsin(down[1])), 30)
    left = rotation_from_ypr(20, 0, 0) @ z
    assert left[0] > 0 and np.isclose(np.degrees(np.arctan2(left[0], left[2])), 20)
    roll = rotation_from_ypr(0, 0, 90) @ np.array([1.0, 0, 0])
    np.testing.assert_allclose(roll, [0, 1, 0], atol=1e-12)
    # A point straight behind and below the camera projects below the image centre.
    cam = FisheyeCamera(640, 480, 200, 200, 319.5, 239.5, rotation=np.eye(3),
                        position=np.array([0, -1.0, 0]))
    (u, v), = cam.project(np.array([[0.0, 0.0, 5.0]]))[0]
    assert np.isclose(u, 319.5) and v > 239.5
