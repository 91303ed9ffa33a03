"""An EC's close-up: the part of the RVM image an EC measures, with its labels written at a
size that reads on paper.

The whole annotated image (:func:`rvmsim.criteria.annotate.annotate`) is made for a screen
column; a printed sheet that shrinks it to a column of a page leaves its text under 1 mm.  A
close-up instead

1. lets the EC draw its measurement on the full RVM image (RVM px);
2. crops the image to what was drawn and the points its labels name, padded, widened to the
   RVM image's aspect and to at least :data:`MIN_CROP_FRACTION` of its width, kept inside it;
3. scales the crop to ``width_px`` and writes the labels there at ``text_px`` px per em
   (:func:`text_px_for_print` gives the size for a printed width and a cap height in mm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .annotate import Box, Label, PlacedLabel, draw_measurements, write_labels
from .canvas import font
from .scoring import EcResult

__all__ = ["Closeup", "closeup", "crop_box", "cap_height_em", "text_px_for_print",
           "MIN_CROP_FRACTION"]

#: A close-up's crop is at least this share of the RVM image's width (what an EC measures
#: keeps some of its surroundings).
MIN_CROP_FRACTION = 0.35
#: Padding around what an EC drew, as a share of the RVM image's width.
_PAD_FRACTION = 0.04


@dataclass(frozen=True)
class Closeup:
    """A close-up as made.

    Attributes
    ----------
    image : (h, width_px, 3) uint8
        The crop, scaled, with the labels written.
    box : (x0, y0, x1, y1)
        The crop in RVM px (exclusive ends).
    scale : float
        Close-up px per RVM px.
    text_px : int
        The labels' size (px per em of ``image``).
    labels : tuple of PlacedLabel
        The labels as written (boxes in px of ``image``).
    dropped : tuple of str
        Texts that found no free place.
    """

    image: np.ndarray
    box: Box
    scale: float
    text_px: int
    labels: tuple[PlacedLabel, ...]
    dropped: tuple[str, ...]


def cap_height_em() -> float:
    """The annotation font's cap height ("H") as a share of its em."""
    size = 200
    x0, y0, x1, y1 = font(size).getbbox("H", anchor="ls")
    return (y1 - y0) / size


def text_px_for_print(width_px: int, print_width_mm: float, cap_height_mm: float) -> int:
    """The label size (px per em) whose capitals are ``cap_height_mm`` tall when an image
    ``width_px`` wide is printed ``print_width_mm`` wide (rounded up)."""
    px_per_mm = width_px / print_width_mm
    return int(math.ceil(cap_height_mm * px_per_mm / cap_height_em()))


def crop_box(drawn: np.ndarray, points: list[tuple[float, float]],
             min_fraction: float = MIN_CROP_FRACTION) -> Box:
    """The crop of an RVM image around the pixels ``drawn`` ((H, W) bool) and ``points``
    (RVM px): their bounding box, padded, widened to the image's aspect and to at least
    ``min_fraction`` of its width, moved inside the image (the whole image when nothing was
    drawn).

    Convention: pixel centres at integer (column, row); the box's ends are exclusive.
    """
    h, w = drawn.shape
    ys, xs = np.nonzero(drawn)
    inside = [(float(x), float(y)) for x, y in points if 0 <= x < w and 0 <= y < h]
    px = [x for x, _ in inside] + xs.tolist()
    py = [y for _, y in inside] + ys.tolist()
    if not px:
        return (0, 0, w, h)
    pad = _PAD_FRACTION * w
    x0, x1 = min(px) - pad, max(px) + 1 + pad
    y0, y1 = min(py) - pad, max(py) + 1 + pad
    cw = max(x1 - x0, (y1 - y0) * w / h, min_fraction * w)
    cw = min(cw, float(w))
    ch = min(cw * h / w, float(h))
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    bx0 = int(round(min(max(cx - cw / 2, 0.0), w - cw)))
    by0 = int(round(min(max(cy - ch / 2, 0.0), h - ch)))
    return (bx0, by0, min(w, bx0 + int(round(cw))), min(h, by0 + int(round(ch))))


def closeup(rvm_color: np.ndarray, rvm_labels: np.ndarray, result: EcResult, *,
            width_px: int, text_px: int,
            min_fraction: float = MIN_CROP_FRACTION) -> Closeup:
    """The close-up of what ``result``'s ECs measure (usually one EC's result).

    Parameters
    ----------
    rvm_color : (H, W, 3) uint8
    rvm_labels : (H, W) uint8
    result : EcResult
        From :func:`rvmsim.criteria.evaluate` on ``rvm_labels``.
    width_px : int
        The close-up's width (px); its height follows the crop's aspect.
    text_px : int
        The labels' size (px per em); see :func:`text_px_for_print`.
    min_fraction : float
        The narrowest crop, as a share of the RVM image's width.

    Returns
    -------
    Closeup
    """
    canvas = draw_measurements(rvm_color, rvm_labels, result)
    drawn = np.any(canvas.image != rvm_color, axis=2)
    x0, y0, x1, y1 = crop_box(drawn, [t.at for t in canvas.texts], min_fraction)
    k = width_px / (x1 - x0)
    size = (int(width_px), max(1, int(round((y1 - y0) * k))))
    crop = canvas.image[y0:y1, x0:x1]
    picture = cv2.resize(crop, size, interpolation=cv2.INTER_AREA if k < 1 else cv2.INTER_CUBIC)
    texts = [Label(t.text, (t.at[0] - x0, t.at[1] - y0), t.colour) for t in canvas.texts]
    placed, dropped, picture = write_labels(np.ascontiguousarray(picture), texts, k, text_px)
    return Closeup(picture, (x0, y0, x1, y1), k, int(text_px), tuple(placed), tuple(dropped))
