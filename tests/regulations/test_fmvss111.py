"""ECs 1-5, 1-6 and 6-1 (rvmsim/regulations/fmvss111/ecs.py) against analytic figures, on real
scenes, cameras, ISP maps and renders."""

from __future__ import annotations

import copy
import functools
import math

import numpy as np
import pytest
import yaml

from rvmsim.criteria import IspView, SceneContext, load_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.pipeline import evaluate_params
from rvmsim.render import render_fisheye
from rvmsim.scene import Display, scene_from_dict

from ..conftest import SCENES

ARCMIN = 180.0 * 60.0 / math.pi


@functools.lru_cache(maxsize=None)
def _doc() -> dict:
    return yaml.safe_load((SCENES / "vehicle_a.yaml").read_text())


def scene_with(**edits):
    """Vehicle A's scene with dotted keys set (``camera.mount.pitch_deg=0``)."""
    doc = copy.deepcopy(_doc())
    for key, value in edits.items():
        node = doc
        *path, last = key.split(".")
        for part in path:
            node = node.setdefault(part, {})
        node[last] = value
    return scene_from_dict(doc, base_dir=SCENES, source="vehicle_a.yaml")


# ---------------------------------------------------------------------------- a level camera
# The camera at the objects' half height, looking straight back (pitch 0), and an ISP whose
# lens model is the camera's (equidistance, f_isp = fx, centred): the RVM image is then an
# exact pinhole view along the camera axis with focal length zoom · W/2 px.
FX = 390.0
HALF_HEIGHT = 0.4


def level_scene(b_position=(0.6, 3.0), display=None):
    edits = {"camera.mount.position": [0.0, -HALF_HEIGHT, -0.14], "camera.mount.pitch_deg": 0.0,
             "test_site.objects": {"B": {"position": list(b_position)}}}
    if display is not None:
        edits["display"] = display
    return scene_with(**edits)


def pinhole_params(zoom: float) -> IspParams:
    return IspParams(fov=180.0, rad=FX * math.pi / 2.0, zoom=zoom)


def _context(scene) -> SceneContext:
    cam = scene.fisheye_camera()
    # 1-6 and 6-1 read no label pixel: a blank fisheye label image stands for the render
    return SceneContext(scene, cam, np.zeros((cam.height, cam.width), np.uint8))


def _measure(scene, params, output, ec):
    ctx = _context(scene)
    crit = load_criteria("fmvss111-full")
    ev = CandidateEvaluator(ctx.fisheye_labels, output, crit, scene=scene, camera=ctx.camera)
    m = ev.measure(params)
    return m.values[ec], m.details[ec], crit


def _bearing_and_half_angle(scene, letter):
    x, z = scene.test_site.object_centre(letter)
    cam = scene.fisheye_camera()
    dx, dz = x - cam.position[0], z - cam.position[2]
    dist = math.hypot(dx, dz)
    return math.atan2(dx, dz), math.asin(scene.test_site.object_diameter / 2 / dist)


@pytest.mark.parametrize("b_position, zoom", [((0.6, 3.0), 1.0), ((-1.2, 5.0), 1.6),
                                              ((0.0, 6.1), 2.5)])
def test_image_size_of_a_cylinder_at_a_known_distance_and_bearing(b_position, zoom):
    display = {"width_mm": 120.0, "height_mm": 90.0, "resolution_px": [1024, 768],
               "eye_distance_mm": 650.0}
    scene = level_scene(b_position, display)
    out = OutputSpec(640, 480, mirror=True)
    value, widths, _ = _measure(scene, pinhole_params(zoom), out, "1-6")
    phi, beta = _bearing_and_half_angle(scene, "B")
    f_out = zoom * out.width / 2.0
    px = f_out * (math.tan(phi + beta) - math.tan(phi - beta))  # pinhole image of the width
    mm = px * min(1024 / 640, 768 / 480) * 120.0 / 1024  # scaled to fit the active area
    arcmin = ARCMIN * 2.0 * math.atan(mm / (2.0 * 650.0))
    assert widths["B"]["px"] == pytest.approx(px, rel=0.02)
    assert widths["B"]["mm"] == pytest.approx(mm, rel=0.02)
    assert widths["B"]["arcmin"] == pytest.approx(arcmin, rel=0.02)
    angles = [w["arcmin"] for w in widths.values()]
    assert value == pytest.approx(min(np.mean(angles) / 5.0, min(angles) / 3.0))


def test_viewing_angle_foreshortens_the_width():
    square = level_scene(display={"eye_distance_mm": 700.0})
    oblique = level_scene(display={"eye_distance_mm": 700.0, "viewing_angle_deg": 40.0})
    out = OutputSpec(640, 480)
    _, w0, _ = _measure(square, pinhole_params(1.0), out, "1-6")
    _, w1, _ = _measure(oblique, pinhole_params(1.0), out, "1-6")
    for c in "ABC":
        expected = ARCMIN * 2 * math.atan(w0[c]["mm"] * math.cos(math.radians(40)) / 1400.0)
        assert w1[c]["arcmin"] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("zoom, scale", [(1.0, 1.0), (2.2, 1.0), (1.5, 0.5)])
def test_magnification_of_a_known_zoom_is_the_analytic_jacobian(zoom, scale):
    scene = level_scene((0.9, 3.0))
    cam = scene.fisheye_camera().scaled(scale)
    params = pinhole_params(zoom).for_input_scale(scale)
    out = OutputSpec(640, 480)
    ctx = SceneContext(scene, cam, np.zeros((cam.height, cam.width), np.uint8))
    crit = load_criteria("fmvss111-full")
    ev = CandidateEvaluator(ctx.fisheye_labels, out, crit, scene=scene, camera=cam)
    widths = ev.measure(params).details["6-1"]
    # at angle θ off the axis a pinhole of focal f_out = zoom·W/2 over an equidistance lens
    # of f = fx·scale stretches radially by f_out·sec²θ / f (more than tangentially,
    # f_out·tanθ/(f·θ)); per px of the full sensor: × scale
    x, z = scene.test_site.object_centre("B")
    ray = cam.scene_to_camera(np.array([[x, -HALF_HEIGHT, z]]))[0]
    theta = math.atan2(math.hypot(ray[0], ray[1]), ray[2])
    f_out = zoom * out.width / 2.0
    expected = f_out / math.cos(theta) ** 2 / (FX * scale) * scale
    assert widths["B"]["magnification"] == pytest.approx(expected, rel=0.01)
    # and the jacobian itself at the axis: the pure zoom f_out / f in both directions
    view = IspView(params, (cam.width, cam.height), out)
    jac = view.output_jacobian(np.array([[(cam.width - 1) / 2, (cam.height - 1) / 2]]))[0]
    assert np.allclose(np.abs(jac), np.eye(2) * f_out / (FX * scale), rtol=1e-4, atol=1e-6)


def test_resolution_margin_uses_both_limits():
    scene = level_scene((0.0, 6.1))
    out = OutputSpec(640, 480)
    value, widths, crit = _measure(scene, pinhole_params(1.0), out, "6-1")
    expected = min(min(2.0 / w["magnification"], w["px_per_deg"] / 2.0)
                   for w in widths.values())
    assert value == pytest.approx(expected)
    # px per degree: the object's RVM width over its angular width seen from the camera
    phi, beta = _bearing_and_half_angle(scene, "B")
    assert widths["B"]["px_per_deg"] == pytest.approx(widths["B"]["px"] / math.degrees(2 * beta),
                                                      rel=1e-3)


# ---------------------------------------------------------------------------- 1-5
def _occluder(tmp_path):
    """A box mesh covering x in [0, 0.5] between the camera and the object at x = 0."""
    import trimesh

    box = trimesh.creation.box(extents=(0.5, 1.4, 0.1))
    box.apply_translation((0.25, -0.7, 0.9))
    path = tmp_path / "occluder.stl"
    box.export(path)
    return path


@pytest.mark.parametrize("hidden", [False, True])
def test_half_hidden_object_shows_half_its_silhouette(tmp_path, hidden):
    edits = {"test_site.objects": {"D": {"position": [0.0, 2.5]}}}
    if hidden:
        edits["vehicle.extra"] = [{"mesh": str(_occluder(tmp_path))}]
    scene = scene_with(**edits)
    cam = scene.fisheye_camera().scaled(0.25)
    images = render_fisheye(scene, camera=cam)
    params = IspParams(fov=180.0, rad=160.0, zoom=0.45, adv_v_shift=0.15)
    frame = evaluate_params(images, params, OutputSpec(320, 180), load_criteria("fmvss111-full"),
                            annotate=False)
    fractions = frame.ec.measurements.details["1-5"][0]
    # D sits on the camera's plane of symmetry (x = 0): the box's edge in that plane hides
    # exactly one half of its silhouette
    if hidden:
        assert fractions["D"] == pytest.approx(50.0, abs=4.0)
    else:
        assert fractions["D"] == 100.0


def test_object_cut_by_the_image_border_is_not_wholly_visible():
    from ..conftest import small_render

    images = small_render("a")
    crit = load_criteria("fmvss111-full")
    wide = IspParams(fov=180.0, rad=160.0, zoom=0.45, adv_v_shift=0.15)
    cut = IspParams(fov=180.0, rad=160.0, zoom=0.45, adv_v_shift=0.15, adv_h_shift=-0.78)
    out = OutputSpec(320, 180)
    full = evaluate_params(images, wide, out, crit, annotate=False).ec
    part = evaluate_params(images, cut, out, crit, annotate=False).ec
    assert full["1-5"].value == 100.0 and full["1-5"].passed
    fractions = part.measurements.details["1-5"][0]
    assert 0.0 < min(fractions.values()) < 100.0 and not part["1-5"].passed


def test_fast_evaluator_equals_the_whole_image_on_the_new_ecs():
    from ..conftest import small_render

    images = small_render("a")
    crit = load_criteria("fmvss111-full")
    out = OutputSpec(320, 180)
    ev = CandidateEvaluator(images.labels, out, crit, scene=images.scene, camera=images.camera)
    rng = np.random.default_rng(4)
    for _ in range(4):
        p = IspParams(fov=180.0, rad=160.0, zoom=float(rng.uniform(0.4, 1.4)),
                      adv_h_shift=float(rng.uniform(-0.3, 0.3)),
                      adv_v_shift=float(rng.uniform(-0.2, 0.3)))
        whole = evaluate_params(images, p, out, crit, annotate=False).ec
        fast = ev(p)
        for ec in ("1-5", "1-6", "6-1"):
            assert fast[ec].value == whole[ec].value


def test_without_a_scene_the_new_ecs_cannot_be_measured():
    from ..conftest import small_render

    images = small_render("a")
    crit = load_criteria("fmvss111-full")
    ev = CandidateEvaluator(images.labels, OutputSpec(320, 180), crit)
    m = ev.measure(IspParams(fov=180.0, rad=160.0, zoom=0.6))
    assert [m.values[ec] for ec in ("1-5", "1-6", "6-1")] == [None, None, None]


def test_display_fit_scale():
    d = Display(width_mm=160.0, height_mm=90.0, resolution_px=(1600, 900))
    # a 4:3 RVM image on a 16:9 panel: the height binds (900 / 480 display px per RVM px)
    assert d.mm_per_rvm_px((640, 480)) == pytest.approx((0.1 * 900 / 480, 0.1 * 900 / 480))
