"""rvmsim.compensation's law against an independent computation: the deviated car rendered
anew and run through the ISP with its per-car values shows the test site where the nominal
car shows it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.camera import rotation_from_ypr
from rvmsim.compensation import (DEFAULT_COMPENSATION, CompensationLaw, Deviation,
                                 deviated_camera, loaded_deviation, measured_deviation,
                                 reference_points, station_error)
from rvmsim.isp import IspParams, OutputSpec, process
from rvmsim.render import render_fisheye
from rvmsim.robust import LoadState, MountSample, sample_camera

from rvmsim.testing.scenes import load_small_scene

SCALE = 1.0
OUTPUT = OutputSpec(1280, 720)  # the display size: thin lines wide enough to compare
#: The site's labelled surfaces (not the vehicle's: its parts are not where the law looks).
SITE_LABELS = [L.BOARD, *range(10, 29), L.GUIDE_SIDE_NEG_X, L.GUIDE_SIDE_POS_X,
               *range(41, 41 + L.MAX_CROSS_LINES)]


def _scene(dev: Deviation = Deviation()):
    base = load_small_scene("a", SCALE)
    m = base.camera.mount
    if dev == Deviation():
        return base
    return load_small_scene("a", SCALE, edit={
        "camera.mount.position": [float(v) for v in
                                  np.asarray(m.position) + np.array(dev.as_offsets()[:3]) / 1000],
        "camera.mount.yaw_deg": m.yaw_deg + dev.yaw_deg,
        "camera.mount.pitch_deg": m.pitch_deg + dev.pitch_deg,
        "camera.mount.roll_deg": m.roll_deg + dev.roll_deg})


def _params() -> IspParams:
    # a wide view that shows the guidelines and every test object
    return dataclasses.replace(IspParams(zoom=0.55, adv_v_shift=-0.1)).for_input_scale(SCALE)


def _centroids(labels: np.ndarray) -> dict[int, tuple[float, float, int]]:
    """Centroid (x, y) and area of each site label wholly inside the image and clear of the
    vehicle's body (which a mount deviation moves against the site: the law keeps the site
    in place, so the body hides a little more or less of what it borders)."""
    import cv2

    out = {}
    h, w = labels.shape
    body = np.isin(labels, [L.BUMPER, L.GARNISH, L.TRUNK]).astype(np.uint8)
    near_body = cv2.dilate(body, np.ones((5, 5), np.uint8)).astype(bool)
    for lab in SITE_LABELS:
        mask = labels == lab
        ys, xs = np.nonzero(mask)
        if xs.size < 1500 or xs.min() == 0 or ys.min() == 0 or xs.max() == w - 1 \
                or ys.max() == h - 1 or (mask & near_body).any():
            continue
        out[lab] = (float(xs.mean()), float(ys.mean()), int(xs.size))
    return out


@pytest.fixture(scope="module")
def nominal():
    sc = _scene()
    p = _params()
    _, rvm = process(None, render_fisheye(sc).labels, p, OUTPUT)
    return sc, p, _centroids(rvm)


@pytest.mark.parametrize("dev", [Deviation(yaw_deg=0.9, pitch_deg=-0.7, roll_deg=0.8),
                                 Deviation(yaw_deg=-0.6, roll_deg=-1.0, pitch_deg=0.5,
                                           x_mm=3.0, y_mm=-3.0, z_mm=2.0)])
def test_the_corrected_image_of_a_deviated_car_shows_the_site_where_the_nominal_does(
        nominal, dev):
    """Within 0.5 px for a turned camera (what the pans and tilt undo); a moved one sees
    the site with parallax no view rotation removes, and the law says how much: the
    surfaces agree within its reported residual (+ 0.5 px)."""
    sc, p, want = nominal
    law = CompensationLaw(sc, p, OUTPUT, DEFAULT_COMPENSATION)
    c = law.correct(dev)
    assert c.within_range and c.params != p
    deviated = render_fisheye(_scene(dev)).labels
    _, before = process(None, deviated, p, OUTPUT)
    _, after = process(None, deviated, c.params, OUTPUT)
    got, moved = _centroids(after), _centroids(before)
    common = [k for k in want if k in got]
    assert len(common) >= 6, "too few site surfaces to compare"
    err = [np.hypot(got[k][0] - want[k][0], got[k][1] - want[k][1]) for k in common]
    moved_too = dev.as_offsets()[:3] != (0.0, 0.0, 0.0)
    allowed = 0.5 + (c.residual_max_px if moved_too else 0.0)
    assert max(err) <= allowed, str({k: (round(e, 2), want[k][2]) for k, e in zip(common, err)})
    assert (c.residual_max_px < 0.25) != moved_too
    # and the deviation did move them: the law had something to correct
    shift = [np.hypot(moved[k][0] - want[k][0], moved[k][1] - want[k][1])
             for k in common if k in moved]
    assert np.median(shift) > 4.0


def test_no_deviation_needs_no_correction(nominal):
    sc, p, _ = nominal
    c = CompensationLaw(sc, p, OUTPUT, DEFAULT_COMPENSATION).correct(Deviation())
    assert all(abs(v) < 1e-6 for v in c.offsets.values())
    assert c.residual_max_px < 1e-6 and c.within_range


def test_a_correction_beyond_the_allowed_range_is_named_and_clipped(nominal):
    sc, p, _ = nominal
    model = dataclasses.replace(DEFAULT_COMPENSATION,
                                ranges=(("h_pan", 0.0, 3.0), ("tilt", -0.5, 0.5)))
    c = CompensationLaw(sc, p, OUTPUT, model).correct(Deviation(roll_deg=1.5))
    assert not c.within_range
    need = c.offsets["tilt"]  # the offset it would have needed
    assert abs(need) > 1.0
    limit = "> 0.5°" if need > 0 else "< -0.5°"
    assert c.exceeded == (f"EOL range exceeded: tilt {need:+.3g}° {limit}",)
    assert c.params.tilt == pytest.approx(p.tilt + np.sign(need) * 0.5)


def test_the_reference_points_lie_in_the_nominal_image(nominal):
    sc, p, _ = nominal
    pts = reference_points(sc, p, OUTPUT)
    assert len(pts) >= 8 and np.allclose(pts[:, 1], 0.0)  # on the ground
    law = CompensationLaw(sc, p, OUTPUT, DEFAULT_COMPENSATION)
    q = law.nominal_px
    assert np.all((q >= 0) & (q <= [OUTPUT.width - 1, OUTPUT.height - 1]))


def test_a_deviation_under_load_is_the_loaded_camera_pose(nominal):
    """loaded_deviation puts the camera where robustness puts a loaded sample's."""
    sc = nominal[0]
    load = LoadState("full", height_mm=-45.0, pitch_deg=0.9)
    offsets = (2.0, -1.0, 3.0, 0.4, -0.3, 0.7)
    sample = MountSample(0, offsets, offsets[:3], load)
    want = sample_camera(sc, sample, scale=1.0)
    got = deviated_camera(sc, loaded_deviation(sc, Deviation.from_offsets(offsets),
                                               load.height_mm, load.pitch_deg))
    np.testing.assert_allclose(got.rotation, want.rotation, atol=1e-12)
    np.testing.assert_allclose(got.position, want.position, atol=1e-12)
    # and an unloaded body changes nothing
    assert loaded_deviation(sc, Deviation(yaw_deg=1.0), 0.0, 0.0) == Deviation(yaw_deg=1.0)
    r = rotation_from_ypr(0.0, 0.9, 0.0)
    assert np.allclose(r @ r.T, np.eye(3))


def test_the_station_error_has_the_models_sigma_and_repeats_per_car():
    model = DEFAULT_COMPENSATION.with_station(0.1, 1.0)
    errs = np.array([station_error(model, 3, i).as_offsets() for i in range(4000)])
    np.testing.assert_allclose(errs.std(axis=0), [1.0] * 3 + [0.1] * 3, rtol=0.06)
    np.testing.assert_allclose(errs.mean(axis=0), 0.0, atol=0.05)
    assert station_error(model, 3, 17) == station_error(model, 3, 17)
    assert station_error(model, 3, 17) != station_error(model, 4, 17)
    perfect = model.with_station(0.0, 0.0)
    d = Deviation(yaw_deg=0.3)
    assert measured_deviation(d, perfect, 3, 17) == d


def test_the_fits_turned_view_is_the_isps_inverse_map(nominal):
    """The rotation-only fit's shortcut (one 3×3 product per step) gives the positions the
    ISP's exact inverse map gives for the same per-car values."""
    from rvmsim.isp import input_to_output
    from rvmsim.isp.exact import isp_rays

    sc, p, _ = nominal
    p = dataclasses.replace(p, h_pan=4.0, v_pan=30.0, tilt=2.0)  # a platform with pans
    law = CompensationLaw(sc, p, OUTPUT, DEFAULT_COMPENSATION)
    cam = deviated_camera(sc, Deviation(yaw_deg=0.7, roll_deg=-0.4))
    uv, _ = cam.project(law.points)
    size = (cam.width, cam.height)
    rng = np.random.default_rng(1)
    for x in rng.uniform(-2.0, 2.0, (5, 3)):
        q, ahead = input_to_output(law.params_at(x), uv, size, OUTPUT)
        got = law._rotated_px(x, isp_rays(p, uv, size))
        np.testing.assert_allclose(got[ahead], q[ahead], atol=1e-6)
