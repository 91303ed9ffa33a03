"""Evaluation criteria: measurements against independent analytic geometry, sigmoids,
criteria files and degenerate images."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
import trimesh
from skimage.measure import regionprops

from rvmsim import labels as L
from rvmsim.criteria import (
    EC_IDS,
    LabelSource,
    Sigmoid,
    default_criteria,
    evaluate,
    load_criteria,
    measure,
    measure_source,
    score_batch,
)
from rvmsim.errors import CriteriaError
from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map, build_map_exact, input_to_output
from rvmsim.scene import GUIDELINE_LIFT_M, board_point, build_parts

from .conftest import bundled_scene, small_render

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
SCALE = 1.0


def _project(letter: str, params: IspParams, pts: np.ndarray) -> np.ndarray:
    """3D scene points → RVM px: cv2.fisheye.projectPoints, then the inverse ISP."""
    cam = small_render(letter, SCALE).camera
    rvec, tvec = cam.rvec_tvec
    uv, _ = cv2.fisheye.projectPoints(np.asarray(pts, float).reshape(-1, 1, 3), rvec, tvec,
                                      cam.K, cam.D, alpha=cam.skew)
    out, ok = input_to_output(params, uv.reshape(-1, 2), (cam.width, cam.height), OUT)
    assert ok.all()
    return out


def _rvm(letter: str):
    img = small_render(letter, SCALE)
    m = build_map(VIEWS[letter], (img.camera.width, img.camera.height), OUT)
    return apply_map(img.labels, m)


def _ring(centre, radius, height, az0, az1, n=400):
    az = np.radians(np.linspace(az0, az1, n))
    return np.stack([centre[0] + radius * np.sin(az), np.full(n, -height),
                     centre[1] + radius * np.cos(az)], 1)


def _polygon_area(uv: np.ndarray) -> float:
    x, y = uv[:, 0], uv[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


@pytest.mark.parametrize("letter", ["a", "b"])
def test_abc_top_margin_matches_projected_rims(letter):
    scene = bundled_scene(letter)
    labels = _rvm(letter)
    m = measure(labels)
    site = scene.test_site
    tops = np.concatenate([_ring(site.object_centre(c), site.object_diameter / 2,
                                 site.object_height, 0, 360) for c in "ABC"])
    v_top = _project(letter, VIEWS[letter], tops)[:, 1].min()
    # The highest object pixel (the square [row − 0.5, row + 0.5]) is within 1 px of v_top.
    assert m.abc_top_row is not None
    assert m.abc_top_row - 1.5 <= v_top <= m.abc_top_row + 1.5
    assert m.values["1-3"] == pytest.approx(100 * m.abc_top_row / OUT.height)


@pytest.mark.parametrize("letter", ["a", "b"])
def test_stripe_areas_match_projected_outlines(letter):
    scene = bundled_scene(letter)
    labels = _rvm(letter)
    m = measure(labels)
    site = scene.test_site
    r = site.object_diameter / 2
    from rvmsim.scene import stripe_azimuth_deg

    total, perimeter = 0.0, 0.0
    for c in "FG":
        centre = site.object_centre(c)
        az = stripe_azimuth_deg(scene, c, centre)
        half = math.degrees(site.stripe_width / r) / 2
        outline = np.concatenate([
            _ring(centre, r, 0.0, az - half, az + half, 100),
            _ring(centre, r, site.object_height, az + half, az - half, 100),
        ])
        uv = _project(letter, VIEWS[letter], outline)
        total += _polygon_area(uv)
        perimeter += np.sum(np.linalg.norm(np.diff(np.vstack([uv, uv[:1]]), axis=0), axis=1))
    area_px = m.values["1-2"] / 1000 * OUT.width * OUT.height
    # Within 1 px of the outline everywhere: the area error is at most the perimeter.
    assert abs(area_px - total) <= perimeter * 1.0
    assert area_px > 200


@pytest.mark.parametrize("letter", ["a", "b"])
def test_guideline_centres_match_projection(letter):
    scene = bundled_scene(letter)
    labels = _rvm(letter)
    m = measure(labels)
    g = scene.test_site.guidelines
    hw = g.line_width / 2
    x0, x1 = g.side_x[0] + hw, g.side_x[1] - hw

    def rect(z):
        xs = np.linspace(x0, x1, 200)
        edge = lambda zz: np.stack([xs, np.full_like(xs, -GUIDELINE_LIFT_M), np.full_like(xs, zz)], 1)
        zs = np.linspace(z - hw, z + hw, 20)
        end = lambda xx: np.stack([np.full_like(zs, xx), np.full_like(zs, -GUIDELINE_LIFT_M), zs], 1)
        return np.concatenate([edge(z - hw), edge(z + hw), end(x0), end(x1)])

    uv2 = _project(letter, VIEWS[letter], rect(g.cross_z[1]))
    analytic_xc = (uv2[:, 0].min() + uv2[:, 0].max()) / 2
    assert m.guide2_center[0] == pytest.approx(analytic_xc, abs=1.0)
    assert m.values["3-1"] == pytest.approx(abs(analytic_xc - (OUT.width - 1) / 2), abs=1.0)
    # Guideline 3's centre height: mid-way between its two long edges at its centre column.
    z3 = g.cross_z[2]
    xm = (x0 + x1) / 2
    mid = _project(letter, VIEWS[letter], np.array([[xm, -GUIDELINE_LIFT_M, z3 - hw],
                                                    [xm, -GUIDELINE_LIFT_M, z3 + hw]]))
    assert m.guide3_center[1] == pytest.approx(mid[:, 1].mean(), abs=1.0)


@pytest.mark.parametrize("letter", ["a", "b"])
def test_board_aspect_matches_projection(letter):
    scene = bundled_scene(letter)
    labels = _rvm(letter)
    m = measure(labels)
    board = scene.test_site.board
    w, h = board.size
    t = np.linspace(-0.5, 0.5, 100)
    outline = np.array([board_point(board, a * w, b * h) for a, b in
                        [(x, -0.5) for x in t] + [(0.5, y) for y in t] + [(x, 0.5) for x in t]
                        + [(-0.5, y) for y in t]])
    uv = _project(letter, VIEWS[letter], outline)
    bx, by, bw, bh = m.board_box
    # Each edge of the box (pixel squares: [bx − 0.5, bx + bw − 0.5]) within 1 px of the
    # projected outline's extreme.
    assert abs((bx - 0.5) - uv[:, 0].min()) <= 1.0 and abs((bx + bw - 0.5) - uv[:, 0].max()) <= 1.0
    assert abs((by - 0.5) - uv[:, 1].min()) <= 1.0 and abs((by + bh - 0.5) - uv[:, 1].max()) <= 1.0
    # The ratio within what ±1 px on each edge allows.
    width, height = np.ptp(uv[:, 0]), np.ptp(uv[:, 1])
    lo, hi = (width - 2) / (height + 2), (width + 2) / (height - 2)
    assert lo <= m.values["4-1"] <= hi


@pytest.mark.parametrize("letter", ["a", "b"])
def test_bumper_heights_match_ray_casting(letter):
    """t_l, t_c, t_r against an exact renderer: per RVM pixel of those columns, the ray
    (inverse ISP, then the camera) is cast with trimesh and the bumper hits counted."""
    scene = bundled_scene(letter)
    img = small_render(letter, SCALE)
    cam = img.camera
    labels = _rvm(letter)
    m = measure(labels)
    parts = build_parts(scene)
    mesh = trimesh.util.concatenate([p.mesh for p in parts])
    face_label = np.concatenate([np.full(len(p.mesh.faces), p.label) for p in parts])
    exact = build_map_exact(VIEWS[letter], (cam.width, cam.height), OUT)
    k = 4
    spans = {"t_l": range(0, k), "t_r": range(OUT.width - k, OUT.width)}
    c0 = int(round(OUT.width / 2 - k / 2))
    spans["t_c"] = range(c0, c0 + k)
    for name, cols in spans.items():
        uv_in = np.array([[exact.map_x[r, c], exact.map_y[r, c]] for c in cols
                          for r in range(OUT.height)])
        inside = ((uv_in[:, 0] >= 0) & (uv_in[:, 0] <= cam.width - 1) & (uv_in[:, 1] >= 0)
                  & (uv_in[:, 1] <= cam.height - 1))
        rays, ok = cam.pixel_rays(uv_in)
        dirs = rays @ cam.rotation.T
        tri = mesh.ray.intersects_first(np.repeat(cam.position[None], len(dirs), 0), dirs)
        hit = np.where(tri >= 0, face_label[np.maximum(tri, 0)], L.SKY)
        bumper = (hit == L.BUMPER) & inside & ok
        t_exact = bumper.sum() / len(cols)
        assert m.bumper_columns[name][2] == pytest.approx(t_exact, abs=1.0), name
        assert t_exact > 5


def test_measurements_agree_with_skimage_regionprops():
    labels = _rvm("a")
    m = measure(labels)
    props = {p.label: p for p in regionprops(labels.astype(np.int32))}
    r0, c0, r1, c1 = props[L.BOARD].bbox
    assert m.board_box == (c0, r0, c1 - c0, r1 - r0)
    fg = sum(props[i].area for i in (L.object_stripe("F"), L.object_stripe("G"),
                                     L.object_patch("F"), L.object_patch("G")) if i in props)
    assert m.values["1-2"] == pytest.approx(1000 * fg / labels.size)
    assert m.values["1-4"] == pytest.approx(1000 * props[L.object_stripe("B")].area / labels.size)
    abc_top = min(props[i].bbox[0] for i in (L.object_body(c) for c in "ABC"))
    abc_top = min([abc_top] + [props[L.object_stripe(c)].bbox[0] for c in "ABC"])
    assert m.abc_top_row == abc_top


# ---------------------------------------------------------------------------- sigmoids
def test_sigmoid_shape():
    s = Sigmoid(c1=3, c2=4, c3=3, c4=8)
    inside = [s(x) for x in np.linspace(5, 7, 9)]
    assert min(inside) > 0.95
    below = [s(x) for x in np.linspace(-5, 4, 50)]
    above = [s(x) for x in np.linspace(8, 20, 50)]
    assert np.all(np.diff(below) > 0) and np.all(np.diff(above) < 0)
    assert s(4) == pytest.approx(0.5, abs=1e-3) and s(8) == pytest.approx(0.5, abs=1e-3)
    assert s(-1e6) == 0.0 and s(1e6) == 0.0  # no overflow, no NaN


def test_one_threshold_forms():
    larger = Sigmoid(c1=0.5, c2=10)  # c4 = +inf
    smaller = Sigmoid(c2=-math.inf, c3=1.17, c4=5)
    assert larger(1e9) == pytest.approx(1.0) and larger(10) == pytest.approx(0.5)
    assert np.all(np.diff([larger(x) for x in range(0, 40)]) > 0)
    assert smaller(-1e9) == pytest.approx(1.0) and smaller(5) == pytest.approx(0.5)
    assert np.all(np.diff([smaller(x) for x in range(0, 20)]) < 0)
    with pytest.raises(ValueError):
        Sigmoid(c2=5, c4=1)


def test_automatic_coefficients_from_range_and_tolerance():
    s = Sigmoid.from_range(4.0, 8.0, tolerance=1.0)
    assert s(4.0) == pytest.approx(0.95, abs=0.005) and s(8.0) == pytest.approx(0.95, abs=0.005)
    assert s(3.0) == pytest.approx(0.05, abs=0.005) and s(9.0) == pytest.approx(0.05, abs=0.005)
    assert s(6.0) > 0.99
    one = Sigmoid.from_range(15.0, None, tolerance=4.0)
    assert one(15) == pytest.approx(0.95) and one(11) == pytest.approx(0.05) and one(1e6) == 1.0


def test_default_criteria_reproduce_the_papers_scores():
    """Section VII-B reports measurement → score pairs for vehicle A; the shipped defaults
    give the same scores to within the paper's rounding."""
    c = default_criteria()
    paper = {"1-2": (26.12, 1.0), "1-3": (25.70, 0.99), "1-4": (0.2, 0.91), "2-1": (3.45, 0.16),
             "2-2": (17.75, 0.009), "2-3": (1.08, 0.99), "3-1": (0.09, 0.99), "3-2": (55, 0.5),
             "4-1": (1.08, 0.7)}
    for ec, (x, s) in paper.items():
        assert c.items[ec].score(x) == pytest.approx(s, abs=0.006), ec
    assert c.items["2-1"].passes(3.45) is False and c.items["3-2"].passes(55) is True


def test_vectorised_scores_agree_with_each_criterion(tmp_path):
    """score_batch (what tuning stores) gives Criterion.score / passes for every EC, for
    measured and missing values, with the defaults and with a customer's file using
    tolerances, one-sided ranges and a switched-off EC."""
    f = tmp_path / "c.yaml"
    f.write_text("criteria:\n  2-1: {range: [3, 9], tolerance: 2}\n"
                 "  1-3: {range: [20, null], tolerance: 5}\n  4-1: {enabled: false}\n")
    rng = np.random.default_rng(3)
    for crit in (default_criteria(), load_criteria(f)):
        values = rng.uniform(-5, 60, size=(400, len(EC_IDS)))
        values[:, [0, 7]] = rng.integers(0, 2, size=(400, 2))  # the binary ECs
        values[rng.random(values.shape) < 0.1] = np.nan
        b = score_batch(values, crit)
        for i in range(len(values)):
            total, ok = 1.0, True
            for j, ec in enumerate(EC_IDS):
                c = crit.items[ec]
                v = None if np.isnan(values[i, j]) else float(values[i, j])
                # (np.tanh and math.tanh may differ in the last bit: 1e-15 absolute)
                assert b.scores[i, j] == pytest.approx(c.score(v), rel=1e-12, abs=1e-15)
                assert bool(b.passed[i, j]) == c.passes(v)
                if c.enabled:
                    total *= c.score(v)
                    ok &= c.passes(v)
            assert b.score[i] == pytest.approx(total, rel=1e-9, abs=1e-15)
            assert bool(b.all_passed[i]) == ok


class _Whole(LabelSource):
    """Every measurement reads the whole image (the reference for the group windows)."""

    def window(self, group):
        return (0, 0, self.shape[1], self.shape[0])


@pytest.mark.parametrize("letter", ["a", "c"])
def test_group_windows_change_no_measurement(letter):
    """measure() reads each group from the box of its 8×8 blocks; the values equal reading
    the whole image, on real RVM label images of many views."""
    img = small_render(letter)
    size = (img.camera.width, img.camera.height)
    rng = np.random.default_rng(11)
    for _ in range(25):
        p = IspParams(fov=rng.uniform(160, 200), rad=rng.uniform(200, 420),
                      zoom=rng.uniform(0.3, 1.3), adv_v_shift=rng.uniform(-0.6, 0.6),
                      adv_h_shift=rng.uniform(-0.3, 0.3), v_shift=rng.uniform(-60, 60))
        w, h = rng.choice([(320, 240), (317, 181)])  # also sizes that are not multiples of 8
        labels = apply_map(img.labels, build_map(p, size, OutputSpec(int(w), int(h))))
        fast, ref = measure(labels), measure_source(_Whole(labels))
        assert fast.values == ref.values
        assert fast.patch_visible == ref.patch_visible and fast.board_box == ref.board_box


# ---------------------------------------------------------------------------- criteria files
def test_customer_file_overrides_and_switches_off(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text(
        "name: OEM X\nupper_region_fraction: 0.4\ncriteria:\n"
        "  2-1: {range: [5, 9], tolerance: 1.0}\n"
        "  4-1: {enabled: false}\n"
    )
    c = load_criteria(path)
    assert c.name == "OEM X" and c.upper_region_fraction == 0.4
    assert c.items["2-1"].low == 5 and c.items["2-1"].sigmoid.c2 == pytest.approx(4.5)
    assert c.items["3-2"] == default_criteria().items["3-2"]
    labels = _rvm("a")
    on, off = evaluate(labels, default_criteria()), evaluate(labels, c)
    assert not off["4-1"].enabled
    expected = np.prod([i.score for i in off.items if i.enabled])
    assert off.score == pytest.approx(expected)
    assert on["4-1"].enabled


@pytest.mark.parametrize("text, words", [
    ("criteria:\n  5-1: {}\n", "unknown EC '5-1'"),
    ("criteria:\n  2-1: {range: [8, 4]}\n", "low <= high"),
    ("criteria:\n  2-1: {tolerance: 1}\n", "needs a range"),
    ("criteria:\n  2-1: {sigmoid: {c1: -1}}\n", "greater than or equal to 0"),
    ("criteria:\n  2-1: {colour: red}\n", "unknown key"),
    ("criteria: [\n", "malformed YAML"),
])
def test_bad_criteria_file(tmp_path, text, words):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(CriteriaError) as info:
        load_criteria(path)
    assert words in str(info.value) and str(path) in str(info.value)
    assert "\n" not in str(info.value)


# ---------------------------------------------------------------------------- degenerate
def _check_defined(result):
    assert set(i.id for i in result.items) == set(EC_IDS)
    for i in result.items:
        assert i.value is None or math.isfinite(i.value)
        assert 0.0 <= i.score <= 1.0 and math.isfinite(i.score)
    assert 0.0 <= result.score <= 1.0


@pytest.mark.parametrize("fill", [L.VOID, L.GROUND, L.SKY])
def test_empty_images_give_defined_failing_scores(fill):
    labels = np.full((360, 640), fill, np.uint8)
    r = evaluate(labels)
    _check_defined(r)
    assert r.score == 0.0 and not r.passed
    for ec in ("1-3", "3-1", "3-2", "4-1"):
        assert r[ec].value is None and r[ec].score == 0.0 and not r[ec].passed
    assert r["1-1"].value == 0.0 and r["2-4"].value == 1.0
    assert r["2-1"].value == 0.0  # no bumper: height 0


def test_cut_and_hidden_objects():
    labels = _rvm("a").copy()
    assert measure(labels).values["1-1"] == 1.0
    # F's lower patch cut by the image border: shift the image so the patch touches it.
    rows, cols = np.nonzero(labels == L.object_patch("F"))
    cut = labels.copy()
    cut[:, cols.max():] = cut[:, cols.max():]  # unchanged copy of the right part
    cut[:, : cols.min() + 1] = L.GROUND
    cut[rows.min():rows.max() + 1, 0] = L.object_patch("F")
    assert measure(cut).values["1-1"] == 0.0 and measure(cut).patch_visible["F"] is False
    # G's patch partly hidden by the bumper.
    hidden = labels.copy()
    rows, cols = np.nonzero(hidden == L.object_patch("G"))
    hidden[rows.max(), cols.min():cols.max() + 1] = L.BUMPER
    assert measure(hidden).values["1-1"] == 0.0
    # One of A, B, C out of frame: EC 1-3 cannot be measured and fails.
    no_c = labels.copy()
    no_c[np.isin(no_c, [L.object_body("C"), L.object_stripe("C")])] = L.GROUND
    r = evaluate(no_c)
    assert r["1-3"].value is None and r["1-3"].score == 0.0
    _check_defined(r)
    # Garnish in the upper region.
    body = labels.copy()
    body[5, 5] = L.GARNISH
    assert measure(body).values["2-4"] == 0.0


def test_rejects_non_label_images():
    with pytest.raises(TypeError):
        measure(np.zeros((10, 10), np.float32))
    with pytest.raises(TypeError):
        measure(np.zeros((10, 10, 3), np.uint8))


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (7, 1), (2, 2)])
def test_tiny_images_are_measured(shape):
    labels = np.full(shape, L.object_patch("F"), np.uint8)
    r = evaluate(labels)
    _check_defined(r)
    assert r["1-1"].value == 0.0  # a patch filling the image touches its border
