"""An EC's close-up (:mod:`rvmsim.criteria.closeup`): the crop holds what was drawn, keeps the
image's aspect and stays inside it; the label size follows the printed width."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria.canvas import font
from rvmsim.criteria.closeup import MIN_CROP_FRACTION, cap_height_em, crop_box, text_px_for_print

W, H = 1280, 720


def _drawn(*boxes: tuple[int, int, int, int]) -> np.ndarray:
    m = np.zeros((H, W), bool)
    for x0, y0, x1, y1 in boxes:
        m[y0:y1, x0:x1] = True
    return m


@pytest.mark.parametrize("boxes,points", [
    ([(600, 300, 620, 330)], []),                      # a small mark mid-image
    ([(0, 0, 5, 5)], []),                              # in a corner: moved inside
    ([(1270, 700, 1280, 720)], [(1000.0, 650.0)]),     # the other corner, with a label point
    ([(100, 200, 1100, 210)], []),                     # a wide line: wider than the minimum
    ([(640, 10, 645, 710)], []),                       # a tall line: the whole height
])
def test_the_crop_holds_what_was_drawn_in_the_images_aspect(boxes, points):
    drawn = _drawn(*boxes)
    x0, y0, x1, y1 = crop_box(drawn, points)
    assert 0 <= x0 < x1 <= W and 0 <= y0 < y1 <= H
    ys, xs = np.nonzero(drawn)
    assert x0 <= xs.min() and xs.max() < x1 and y0 <= ys.min() and ys.max() < y1
    for x, y in points:
        assert x0 <= x < x1 and y0 <= y < y1
    assert x1 - x0 >= MIN_CROP_FRACTION * W - 1
    assert (x1 - x0) / (y1 - y0) == pytest.approx(W / H, abs=0.02)


def test_nothing_drawn_is_the_whole_image():
    assert crop_box(np.zeros((H, W), bool), []) == (0, 0, W, H)


def test_the_label_size_gives_the_asked_cap_height_on_paper():
    """A capital H written at the size asked for an 800 px image printed 88 mm wide is at
    least 2.8 mm tall on paper (measured in the glyph's own pixels)."""
    px = text_px_for_print(800, 88.0, 2.8)
    _, top, _, bottom = font(px).getbbox("H", anchor="ls")
    assert (bottom - top) * 88.0 / 800 >= 2.8 > (bottom - top - 2) * 88.0 / 800
    assert 0.6 < cap_height_em() < 0.8
