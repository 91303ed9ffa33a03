"""Annotation: every EC draws its own measurement, a plugin EC included; labels placed without
overlap inside the picture, written in a font that has the units' glyphs, at a legible size;
the panel lists every selected EC and is exactly as large as its content."""

from __future__ import annotations

import dataclasses
import functools
import itertools
import shutil
from pathlib import Path

import numpy as np
import pytest

from rvmsim.criteria import (PASS, FAIL, EcValue, annotate, default_criteria, evaluate,
                             load_criteria)
from rvmsim.criteria.annotate import (MIN_TEXT_PX, TEXT_PX, Annotation, annotation,
                                      panel_rows, place_labels, spelled_name)
from rvmsim.criteria.canvas import font, font_path
from rvmsim.isp import IspParams, OutputSpec, process
from rvmsim.pipeline import evaluate_params

from ..conftest import small_render

EXAMPLE = Path(__file__).with_name("ec_plugin_example.py")
PANEL_BG = (32, 32, 32)


def _rvm():
    img = small_render("a")
    p = IspParams(fov=180, rad=300, zoom=0.5, adv_v_shift=0.2)
    return process(img.color, img.labels, p, OutputSpec(320, 240))


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _assert_laid_out(boxes, bounds) -> None:
    """No two boxes overlap, every box inside [0, W) × [0, H)."""
    w, h = bounds
    for box in boxes:
        assert 0 <= box[0] < box[2] <= w and 0 <= box[1] < box[3] <= h, (box, bounds)
    for a, b in itertools.combinations(boxes, 2):
        assert not _overlap(a, b), (a, b)


@functools.lru_cache(maxsize=None)
def _scene_frames():
    """Real renders: vehicles A, B, C with the paper's ECs and the fmvss111-full set, at
    three output sizes (small, the tuning's 640 × 360, the display's 1280 × 720)."""
    # vehicle A tuned (a 640 × 360 run), on half the sensor
    p = IspParams(fov=182.4, rad=682.2, h_shift=0.35, v_shift=50.8, zoom=0.679,
                  adv_v_shift=-0.159, adv_h_scale=0.621, adv_v_scale=0.978).for_input_scale(0.5)
    out = []
    for letter, crit, size in (("a", "fmvss111-full", (320, 240)), ("a", None, (640, 360)),
                               ("b", "fmvss111-full", (640, 360)), ("c", None, (1280, 720))):
        criteria = default_criteria() if crit is None else load_criteria(crit)
        fr = evaluate_params(small_render(letter), p, OutputSpec(*size), criteria,
                             annotate=False)
        out.append((f"{letter} {crit} {size}", fr))
    return out


def _requested(fr) -> int:
    """How many labels the ECs ask for (a canvas that records them)."""
    from rvmsim.criteria import Canvas

    canvas = Canvas(fr.color.copy(), fr.labels, 1.0, 1)
    defs = fr.ec.definitions
    for item, ec in zip(fr.ec.items, defs):
        if ec.annotate is not None:
            ec.annotate(canvas, item, fr.ec.measurements.details.get(item.id))
    return len(canvas.texts)


def test_labels_on_real_scenes_do_not_overlap_and_stay_in_the_picture():
    for name, fr in _scene_frames():
        a = annotation(fr.color, fr.labels, fr.ec)
        x0, y0, x1, y1 = a.picture
        assert (x0, y0) == (0, 0)
        boxes = [lab.box for lab in a.labels]
        _assert_laid_out(boxes, (x1, y1))
        assert not a.dropped, name
        n = _requested(fr)
        assert len(a.labels) == n and n >= 8, name
        # no box covers another label's point (its marker)
        for lab, other in itertools.product(a.labels, a.labels):
            px, py = other.at
            b = lab.box
            assert not (b[0] <= px < b[2] and b[1] <= py < b[3]), (name, lab.text, other.text)
        # spelled out: no cryptic names left
        texts = " | ".join(lab.text for lab in a.labels)
        for cryptic in ("t_l", "t_r", "t_c", "o/oo", "3-2 y", "4-1 w/h"):
            assert cryptic not in texts, (name, texts)
        if "bumper height, left edge" not in texts:
            pytest.fail(f"{name}: no spelled-out bumper label in {texts}")


def test_crowded_labels_are_moved_apart_with_leaders_inside_the_bounds():
    rng = np.random.default_rng(3)
    bounds = (400, 300)
    # 30 labels crowded around three points, one right at a corner
    points = [(200.0, 150.0)] * 10 + [(205.0, 152.0)] * 10 + [(399.0, 0.0)] * 10
    sizes = [(int(rng.integers(40, 140)), 18) for _ in points]
    boxes = place_labels(sizes, points, bounds)
    assert all(b is not None for b in boxes)
    _assert_laid_out(boxes, bounds)
    for (w, h), b in zip(sizes, boxes):
        assert (b[2] - b[0], b[3] - b[1]) == (w, h)
    # the first at each point sits next to it; later ones farther, nearest first
    def dist(p, b):
        return np.hypot(max(b[0] - p[0], 0, p[0] - b[2]), max(b[1] - p[1], 0, p[1] - b[3]))
    assert dist(points[0], boxes[0]) <= 6 and dist(points[20], boxes[20]) <= 6
    assert max(dist(p, b) for p, b in zip(points, boxes)) > 20
    # over-full: what does not fit is refused, what fits still does not overlap
    many = place_labels([(150, 40)] * 40, [(100.0, 100.0)] * 40, (300, 200))
    placed = [b for b in many if b is not None]
    assert 4 <= len(placed) < 40 and many[0] is not None
    _assert_laid_out(placed, (300, 200))
    assert place_labels([(500, 10)], [(0.0, 0.0)], (300, 200)) == [None]


def test_the_font_has_the_units_glyphs_and_the_panel_uses_them():
    path = font_path()
    assert path.suffix == ".ttf" and path.is_file()
    f = font(TEXT_PX)
    missing = f.getmask("\ue000")  # a private-use code point: the font's "no glyph" box
    for glyph in "‰°×≥≤′–✓✗":
        mask = f.getmask(glyph)
        assert mask.getbbox() is not None, glyph
        assert (mask.size != missing.size
                or bytes(mask) != bytes(missing)), f"{glyph!r} is drawn as a missing glyph"
    color, labels = _rvm()
    r = evaluate(labels)
    rows = {row[0]: row for row in panel_rows(r)}
    assert rows["1-2"][2].endswith(" ‰") and "‰" in rows["1-2"][3]
    assert rows["1-2"][1] == "F, G stripe area ratio"
    item = r["1-2"]
    assert item.margin is not None
    sign = "+" if item.margin >= 0 else "−"
    assert rows["1-2"][4].startswith(sign) and rows["1-2"][5] == ("pass" if item.passed
                                                                  else "fail")


def test_margin_is_the_signed_distance_to_the_nearer_limit():
    def v(value, low, high):
        return EcValue("x", "x", value, "%", low, high, 1.0, True, True).margin

    assert v(6.0, 4.0, 8.0) == 2.0 and v(7.5, 4.0, 8.0) == 0.5 and v(9.0, 4.0, 8.0) == -1.0
    assert v(3.0, 4.0, None) == -1.0 and v(3.0, None, 5.0) == 2.0 and v(4.0, 4.0, None) == 0
    assert v(None, 4.0, 8.0) is None and v(3.0, None, None) is None


def test_one_margin_text_everywhere_yes_no_ecs_read_tick_or_cross():
    """EcValue.margin_text, which the report, the sign-off, the panel and the console
    follow: ✓/✗ for a yes/no EC (a range of one value), never "+0"; signed otherwise."""
    def t(value, low, high, passed, unit=""):
        return EcValue("x", "x", value, "px", low, high, 1.0, passed, True).margin_text(unit)

    assert t(1.0, 1.0, 1.0, True) == "✓" and t(0.0, 1.0, 1.0, False) == "✗"
    assert t(None, 1.0, 1.0, False) == "—"
    assert t(6.5, None, 5.0, False, " px") == "-1.5 px" and t(2.0, 0.0, 5.0, True) == "+2"
    assert t(3.0, None, None, True) == "—" and t(None, 0.0, 5.0, False) == "—"
    color, labels = _rvm()
    rows = {row[0]: row for row in panel_rows(evaluate(labels))}
    r = evaluate(labels)
    for ec in ("1-1", "2-4"):  # the paper's yes/no ECs
        assert r[ec].yes_no and rows[ec][4] == ("✓" if r[ec].passed else "✗")


def _longest_background_run(rows: np.ndarray) -> int:
    """Longest run of consecutive rows that are entirely the panel's background."""
    blank = np.all(rows == np.array(PANEL_BG), axis=(1, 2))
    best = run = 0
    for b in blank:
        run = run + 1 if b else 0
        best = max(best, run)
    return best


def test_no_empty_strip_and_the_panel_fits_its_content():
    for name, fr in _scene_frames():
        a = annotation(fr.color, fr.labels, fr.ec)
        img = a.image
        x0, y0, x1, y1 = a.picture
        # under the picture's columns, never a band of empty rows (the old 98 px strip)
        assert _longest_background_run(img[:, x0:x1]) <= TEXT_PX, name
        px0, py0, px1, py1 = a.panel
        assert img.shape[:2] == (max(y1, py1), max(x1, px1)), name
        panel = img[py0:py1, px0:px1]
        ink = np.nonzero(np.any(panel != np.array(PANEL_BG), axis=(1, 2)))[0]
        if py0 == y1:  # under the picture: exactly as tall as its text
            assert py1 - py0 - ink.max() <= TEXT_PX, name
        else:  # beside: no taller than the picture, whose rows it spans
            assert (py0, py1) == (0, y1) and px0 == x1, name
        assert img.shape[1] <= 1200, name


def test_text_is_at_least_the_minimum_size_where_pages_show_it():
    for name, fr in _scene_frames():
        a = annotation(fr.color, fr.labels, fr.ec)
        assert a.font_px == TEXT_PX >= MIN_TEXT_PX
        # pages show images up to 1200 px wide at their own size (tests/report checks the
        # pages in a browser); the ink of a label with ascenders and descenders is as tall
        # as the font says
        assert a.image.shape[1] <= 1200
        lab = next(lab for lab in a.labels if lab.text.startswith("bumper height"))
        x0, y0, x1, y1 = lab.box
        box = a.image[y0 + 1 : y1 - 1, x0 + 1 : x1 - 1].astype(int)
        bright = np.nonzero((box.max(axis=2) > 110).any(axis=1))[0]  # box: <= 1/4 of 255
        assert bright.max() - bright.min() + 1 >= MIN_TEXT_PX, (name, lab.text)


def test_spelled_names():
    assert spelled_name("fg_lower_patches_visible") == "F, G lower patches visible"
    assert spelled_name("guide3_height_ratio") == "guideline 3 height ratio"
    assert spelled_name("board_centre_offset") == "board centre offset"


def test_plugin_ec_draws_its_measurement(tmp_path):
    shutil.copy(EXAMPLE, tmp_path / "ec.py")
    crit = tmp_path / "c.yaml"
    crit.write_text("plugins: [ec.py]\n")
    color, labels = _rvm()
    mine, paper = evaluate(labels, load_criteria(crit)), evaluate(labels, default_criteria())
    item = mine["acme-board-centred"]
    assert item.value is not None
    a, b = annotation(color, labels, mine), annotation(color, labels, paper)
    assert a.scale == b.scale == 2  # 320 px enlarged to 640
    k = int(a.scale)
    h = labels.shape[0] * k
    assert a.picture == b.picture and a.image.shape[0] >= b.image.shape[0]
    assert "acme-board-centred" in {r[0] for r in panel_rows(mine)}
    # the example draws a vertical line through the board's centre, in its status colour
    x = k * int(round(mine.measurements.details["acme-board-centred"]))
    colour = np.array(PASS if item.passed else FAIL)
    line = np.all(a.image[:h, x] == colour, axis=1).sum()
    assert line > 0.7 * h and np.all(b.image[:h, x] == colour, axis=1).sum() < 0.3 * h
    # and its label; the built-ins draw the same with or without it (but where its line
    # and label are)
    (mine_label,) = [lab for lab in a.labels if lab.text.startswith("board dx")]
    assert [lab.box for lab in a.labels if lab is not mine_label] == [lab.box for lab in
                                                                      b.labels]
    differs = np.any(a.image[:h, : a.picture[2]] != b.image[:h, : b.picture[2]], axis=2)
    differs[:, max(0, x - 2 * k) : x + 3 * k] = False
    lx0, ly0, lx1, ly1 = mine_label.box
    differs[ly0:ly1, lx0:lx1] = False
    assert differs.sum() < 0.005 * differs.size


def test_results_without_definitions_draw_the_builtins():
    color, labels = _rvm()
    r = evaluate(labels)
    bare = dataclasses.replace(r, definitions=())
    assert np.array_equal(annotate(color, labels, bare), annotate(color, labels, r))
    drawn: Annotation = annotation(color, labels, r)
    plain = np.repeat(np.repeat(color, 2, axis=0), 2, axis=1)
    assert drawn.image[: plain.shape[0], : plain.shape[1]].shape == plain.shape
    assert not np.array_equal(drawn.image[: plain.shape[0], : plain.shape[1]], plain)
