"""What the per-car law judges a car by: the station's errors as warps of the true image."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.camera import rotation_from_ypr
from rvmsim.compensation import DEFAULT_COMPENSATION
from rvmsim.criteria import default_criteria
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.percar import (EdgeWarp, ImagePicture, SplitEvaluator, TurnWarp, body_ecs,
                           ec_uncertainty)
from rvmsim.pipeline import make_evaluator
from rvmsim.render import render_fisheye

from rvmsim.testing.scenes import load_small_scene


@pytest.fixture(scope="module")
def car():
    scene = load_small_scene("a", 0.25)
    return scene, render_fisheye(scene)


def test_a_turn_warp_reads_the_unturned_image_where_the_turned_camera_looks(car):
    """Independent check: scene points projected by the turned and the unturned camera;
    the warp takes the first pixel to the second (a turn about the optical centre only)."""
    scene, images = car
    cam = images.camera
    turn = rotation_from_ypr(0.4, -0.3, 0.5) @ rotation_from_ypr(0, 0, 0).T
    turned = type(cam)(cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy, cam.k, cam.skew,
                       cam.fov_deg, cam.rotation @ turn, cam.position)
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(-3, 3, 200), np.zeros(200), rng.uniform(0.5, 8, 200)]
    q_turned, ok1 = turned.project(pts)
    q_true, ok2 = cam.project(pts)
    ok = ok1 & ok2
    got = TurnWarp(cam, turn)(q_turned[ok])
    assert ok.sum() > 100
    np.testing.assert_allclose(got, q_true[ok], atol=1e-6)
    np.testing.assert_allclose(TurnWarp(cam, np.eye(3))(q_true[ok]), q_true[ok], atol=1e-9)


def test_an_edge_warp_moves_rows_by_its_offset_and_tilt():
    w = EdgeWarp(0.5, 2.0, 100.0, 50.0)
    xy = np.array([[100.0, 10.0], [150.0, 10.0], [50.0, 10.0]])
    np.testing.assert_allclose(w(xy), [[100.0, 9.5], [150.0, 7.5], [50.0, 11.5]])


def test_the_split_evaluator_is_the_evaluator_and_reads_each_part_through_its_warp(car):
    scene, images = car
    crit = default_criteria()
    out = OutputSpec(640, 360)
    params = IspParams(zoom=0.55, adv_v_shift=-0.1).for_input_scale(0.25)
    split = SplitEvaluator(images, out, crit)
    whole = make_evaluator(images, out, crit, record=out)
    np.testing.assert_array_equal(split.values(params), whole.values(params))
    body = body_ecs(crit)
    assert [e for e, b in zip(crit.ids, body) if b] == ["2-1", "2-2", "2-3", "2-4"]
    # the body read through a warp that moves it 3 rows: the bumper's ECs change, the
    # site's do not; the same warp on the whole image is what the full path measures on an
    # image moved so
    warp = EdgeWarp(3.0, 0.0, images.camera.cx, images.camera.width / 2)
    got = split.values(params, None, warp)
    np.testing.assert_array_equal(got[~body], whole.values(params)[~body])
    moved = np.full_like(images.labels, L.VOID)
    moved[3:] = images.labels[:-3]
    want = make_evaluator(type(images)(color=images.color, labels=moved, camera=images.camera,
                                       scene=images.scene), out, crit, record=out).values(params)
    np.testing.assert_allclose(got[body], want[body], atol=2 * 100 / 360)
    assert not np.allclose(got[body][:3], whole.values(params)[body][:3])


def test_the_split_parts_share_one_map_and_measure_as_each_alone(car):
    """The split evaluator builds the candidate's map once for its two parts; each part's
    values are those of an evaluator of its ECs alone building its own map, with a turn on
    the site and an edge error on the body."""
    from rvmsim.percar import GridWarp, criteria_subset

    scene, images = car
    crit = default_criteria()
    out = OutputSpec(640, 360)
    cam = images.camera
    site = GridWarp(TurnWarp(cam, rotation_from_ypr(0.3, -0.2, 0.25)), (cam.width, cam.height))
    edge = EdgeWarp(1.5, -0.5, cam.cx, cam.width / 2)
    split = SplitEvaluator(images, out, crit)
    body = body_ecs(crit)
    for params in (IspParams(zoom=0.55, adv_v_shift=-0.1), IspParams(h_pan=3.0, v_pan=40.0),
                   IspParams(tilt=2.0, zoom=0.7)):
        p = params.for_input_scale(0.25)
        got = split.values(p, site, edge)
        for part, warp in ((~body, site), (body, edge)):
            alone = make_evaluator(images, out, criteria_subset(crit, part), record=out)
            np.testing.assert_array_equal(got[part], alone.values(p, warp))


def test_each_error_source_reaches_only_its_ecs(car):
    """The station's pose σ gives the site's ECs an uncertainty, the edge σ the body's."""
    scene, images = car
    crit = default_criteria()
    out = OutputSpec(640, 360)
    params = IspParams(zoom=0.55, adv_v_shift=-0.1).for_input_scale(0.25)
    picture = ImagePicture(SplitEvaluator(images, out, crit), 1.0)
    body = body_ecs(crit)
    zero, _ = ec_uncertainty(picture, params, DEFAULT_COMPENSATION.with_station(0, 0, 0),
                             images.camera)
    assert not zero.any()
    pose, _ = ec_uncertainty(picture, params, DEFAULT_COMPENSATION.with_station(0.3, 0, 0),
                             images.camera)
    edge, _ = ec_uncertainty(picture, params, DEFAULT_COMPENSATION.with_station(0, 0, 1.0),
                             images.camera)
    assert not pose[body].any() and pose[~body].any()
    assert not edge[~body].any() and edge[body].any()


def test_station_errors_drawn_once_give_the_same_uncertainty(car):
    """The station's errors drawn once (as a tuning run does for all its candidates) give
    every setting the uncertainty drawing them each time gives, and a law made with them is
    the law made without."""
    from rvmsim.compensation import DEFAULT_COMPENSATION as model
    from rvmsim.percar import make_law, nominal_draws, station_draws

    scene, images = car
    crit = default_criteria()
    out = OutputSpec(640, 360)
    picture = ImagePicture(SplitEvaluator(images, out, crit), 0.25)
    drawn = station_draws(model, images.camera, 0.25)
    assert len(drawn.warps) == drawn.draws > 0
    assert not station_draws(model.with_station(0, 0, 0), images.camera).warps
    for params in (IspParams(zoom=0.55, adv_v_shift=-0.1), IspParams(h_pan=2.0, v_pan=10.0)):
        fresh = ec_uncertainty(picture, params, model, images.camera)
        again = ec_uncertainty(picture, params, model, images.camera, station=drawn)
        np.testing.assert_array_equal(fresh[0], again[0])
        np.testing.assert_array_equal(fresh[1], again[1])
        assert fresh[0].any()
        full = load_small_scene("a", 1.0)
        law = make_law(full, params, out, model, crit, picture, images.camera)
        kept = make_law(full, params, out, model, crit, picture, images.camera,
                        station=nominal_draws(full, model, picture, images.camera))
        np.testing.assert_array_equal(law.uncertainty, kept.uncertainty)
        assert law.target == kept.target


def test_a_gridded_turn_warp_is_the_turn_warp_inside_the_field(car):
    """Sampled every 8 px and interpolated, the station's turn warp (0.3° about every axis)
    moves positions inside the lens's field where the exact one does, within 0.005 px."""
    from rvmsim.percar import GridWarp

    _, images = car
    cam = images.camera
    turn = rotation_from_ypr(0.3, 0.3, 0.3) @ rotation_from_ypr(0, 0, 0).T
    exact = TurnWarp(cam, turn)
    grid = GridWarp(exact, (cam.width, cam.height))
    rng = np.random.default_rng(2)
    xy = np.c_[rng.uniform(0, cam.width - 1, 4000), rng.uniform(0, cam.height - 1, 4000)]
    _, inside = cam.pixel_rays(xy)
    # away from the field's edge, where the exact warp stops moving positions
    r = np.hypot((xy[:, 0] - cam.cx) / cam.fx, (xy[:, 1] - cam.cy) / cam.fy)
    keep = inside & (r < 0.9 * r[inside].max())
    np.testing.assert_allclose(grid(xy[keep]), exact(xy[keep]), atol=0.005)
