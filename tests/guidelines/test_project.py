"""Guidelines through the lens and the ISP, checked against independent computations:
cv2.fisheye.projectPoints for the lens, the ISP's forward map for its inverse."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rvmsim.guidelines import (compute_guidelines, guideline_view, project_lines, running_gear,
                               static_lines, steering_angles, GroundLine)
from rvmsim.guidelines.project import display_to_ground
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.isp.exact import map_points
from rvmsim.scene import GuidelineSpec
from tests.conftest import bundled_scene

# a setting that turns and zooms the view (all of the map's steps do something)
PARAMS = IspParams(fov=185.0, rad=600.0, h_shift=12.0, v_shift=-20.0, h_pan=8.0, v_pan=30.0,
                   zoom=1.2, tilt=3.0, adv_h_shift=0.05, adv_v_shift=-0.1, adv_h_scale=1.1,
                   adv_v_scale=0.9)


@pytest.mark.parametrize("letter", ["a", "b", "d"])
def test_display_points_map_back_onto_the_lens_projection(letter: str) -> None:
    scene = bundled_scene(letter)
    cam = scene.fisheye_camera()
    view = guideline_view(scene, PARAMS, OutputSpec(mirror=True))
    gset = compute_guidelines(scene, view, (0.0, 300.0))
    pieces = [p for line in gset.lines() for p in line.pieces]
    uv = np.concatenate([p.uv_px for p in pieces])
    ground = np.concatenate([p.ground_m for p in pieces])
    assert len(uv) > 500
    pts = np.column_stack([ground[:, 0], np.zeros(len(ground)), ground[:, 1]])
    assert cam.lens_model in ("equidistance", "kannala_brandt")  # cv2's model (k = 0 or k)
    rvec, tvec = cam.rvec_tvec
    fish, _ = cv2.fisheye.projectPoints(pts.reshape(-1, 1, 3), rvec, tvec, cam.K, cam.D,
                                        alpha=cam.skew)
    fish = fish.reshape(-1, 2)
    # the ISP's forward map (display → fisheye) lands where the lens put the ground point
    ux, vy, _ = map_points(PARAMS, uv[:, 0], uv[:, 1], (cam.width, cam.height), view.output)
    err = np.hypot(ux - fish[:, 0], vy - fish[:, 1])
    assert err.max() < 1e-3
    # and the display point looks at its ground point
    back, hits = display_to_ground(view, uv)
    assert hits.all()
    assert np.abs(back - ground).max() < 1e-6


def test_lines_are_cut_at_the_border_of_the_picture() -> None:
    scene = bundled_scene("a")
    # a narrow view: the lines run out of it
    params = IspParams(zoom=2.5)
    view = guideline_view(scene, params, OutputSpec())
    w, h = view.output.width, view.output.height
    lines = static_lines(3.0, GuidelineSpec())
    shown = project_lines(view, lines)
    ends = []
    for line in shown:
        for piece in line.pieces:
            inside = ((piece.uv_px[:, 0] >= -0.5 - 1e-9) & (piece.uv_px[:, 0] <= w - 0.5 + 1e-9)
                      & (piece.uv_px[:, 1] >= -0.5 - 1e-9) & (piece.uv_px[:, 1] <= h - 0.5 + 1e-9))
            assert inside.all()
            ends += [piece.uv_px[0], piece.uv_px[-1]]
    on_border = [min(abs(u + 0.5), abs(u - (w - 0.5)), abs(v + 0.5), abs(v - (h - 0.5))) < 1e-3
                 for u, v in ends]
    assert sum(on_border) >= 2  # the view cuts some lines
    # a line far outside the view is not shown at all
    far = GroundLine("far", "mark", (1.0, 1.0, 1.0), np.array([[-1.0, -30.0], [1.0, -30.0]]))
    assert project_lines(view, [far])[0].pieces == ()


def test_steering_angle_specs() -> None:
    gear = running_gear(bundled_scene("a"))
    assert len(steering_angles(gear, "-540:540:10")) == 109
    assert steering_angles(gear, "0,90,-90") == (0.0, 90.0, -90.0)
    whole = steering_angles(gear)
    assert whole[0] == pytest.approx(-gear.steering_range_deg)
    assert whole[-1] == pytest.approx(gear.steering_range_deg)
    assert 0.0 in whole
    for bad in ("1:2", "5:1:1", "0:10:0", "a,b", "0:1e9:1e-3"):
        with pytest.raises(ValueError):
            steering_angles(gear, bad)
