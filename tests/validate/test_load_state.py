"""Validation of a scene with a ``load_state``: the pose search starts from the camera as
the loaded scene shows it, and the corrected mount is given on the unloaded body."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.render import render_fisheye
from rvmsim.validate import ValidationSettings, validate

from rvmsim.testing.captures import make_scene, scene_dict

FULL = {"name": "full load", "height_mm": -45.0, "pitch_deg": 0.9}


def test_a_capture_of_the_loaded_car_needs_no_correction_of_the_loaded_scene():
    d = scene_dict()
    d["load_state"] = FULL
    loaded = make_scene(d)
    truth = render_fisheye(loaded)
    res = validate(loaded, truth.color.copy(), ValidationSettings(), synthetic=truth)
    c = res.correction
    assert res.passed and c.d_position_norm_mm < 5.0 and c.max_d_angle_deg < 0.1
    m = loaded.camera.mount  # the corrected mount is the file's, on the unloaded body
    np.testing.assert_allclose(c.position_m, m.position, atol=0.005)
    assert (c.yaw_deg, c.pitch_deg, c.roll_deg) == pytest.approx(
        (m.yaw_deg, m.pitch_deg, m.roll_deg), abs=0.1)
    # the re-render at the corrected mount keeps the loaded body: the same picture
    assert res.edges_after is not None and res.edges_after.chamfer_px < 0.2


def test_the_unloaded_scene_sees_the_load_as_a_lower_camera_pitched_down():
    d = scene_dict()
    d["load_state"] = FULL
    truth = render_fisheye(make_scene(d))
    res = validate(make_scene(scene_dict()), truth.color.copy(),
                   ValidationSettings(rerender=False))
    c = res.correction
    assert c.d_position_mm[1] == pytest.approx(45.0, abs=5.0)  # y toward the ground
    assert c.d_pitch_deg == pytest.approx(0.9, abs=0.1)
