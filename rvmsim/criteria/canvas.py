"""What an EC's annotate function draws on (:class:`Canvas`), its colours, the labels it asks
for (:class:`Label`) and the font they are written in; on its own so that EC definitions can
name it without importing the annotation.

Shapes (lines, markers, fills) are drawn on the RVM image straight away, in RVM px.  Text is
not: :meth:`Canvas.text` queues a :class:`Label` at a point, and :func:`rvmsim.criteria.annotate`
places every label afterwards without overlap (moving it, with a leader line, where its first
place is taken) and writes it with a TrueType font (real ‰, °, ×, ≥ glyphs) on a dark box, at
a size that reads on the page that shows the picture.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path

import importlib.util

import numpy as np
from PIL import ImageFont

from ..errors import RvmsimError
from .values import EcValue


__all__ = ["Canvas", "Colour", "Label", "PASS", "FAIL", "OFF", "INK", "font", "font_path",
           "unit_text"]

#: RGB colour.
Colour = tuple[int, int, int]
PASS: Colour = (40, 170, 60)
FAIL: Colour = (220, 40, 40)
OFF: Colour = (140, 140, 140)
INK: Colour = (255, 255, 255)


@dataclass(frozen=True)
class Label:
    """A text an EC asks for, written later by the annotation's label layout.

    Parameters
    ----------
    text : str
        Any Unicode text (one line).
    at : (x, y)
        RVM px: the point the text belongs to.  Its first choice of place is to the upper
        right of it (the baseline starting there); if taken, a free place around it, else
        anywhere free in the image with a leader line back to it.
    colour : Colour
        Usually the EC's status colour (:meth:`Canvas.status`).
    """

    text: str
    at: tuple[float, float]
    colour: Colour = INK


@dataclass(frozen=True)
class Canvas:
    """What an EC's annotate function draws on.

    Parameters
    ----------
    image : (H, W, 3) uint8
        The RVM colour image, drawn on in place (RGB).
    labels : (H, W) uint8
        The RVM label image the measurements were made on.
    text_scale : float
        A size factor that suits the image (≈ image size / 900; kept for plugins that
        space their drawings by it).
    line_width : int
        Line width (px) that suits the image size.
    texts : list of Label
        The labels asked for so far (:meth:`text`), in order.

    Notes
    -----
    Convention: pixel centres at integer (column, row), as in the measurements.
    """

    image: np.ndarray
    labels: np.ndarray
    text_scale: float
    line_width: int
    texts: list[Label] = field(default_factory=list)

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) px."""
        return (int(self.labels.shape[0]), int(self.labels.shape[1]))

    def text(self, text: str, org: tuple[float, float], colour: Colour = INK,
             scale: float | None = None, thick: int = 1) -> None:
        """Ask for a label ``text`` at the point ``org`` (RVM px): written after every EC
        has drawn, where it overlaps no other label (:class:`Label`).  ``scale`` and
        ``thick`` are ignored (the annotation sizes all text alike)."""
        self.texts.append(Label(str(text), (float(org[0]), float(org[1])), colour))

    def fill(self, mask: np.ndarray, colour: Colour, alpha: float = 0.55) -> None:
        """Blend ``colour`` into the pixels where ``mask`` (H, W) is true."""
        if np.any(mask):
            img = self.image
            img[mask] = (img[mask] * (1 - alpha) + np.asarray(colour) * alpha).astype(np.uint8)

    @staticmethod
    def status(item: EcValue) -> Colour:
        """:data:`OFF` for a switched-off EC, else :data:`PASS` or :data:`FAIL`."""
        if not item.enabled:
            return OFF
        return PASS if item.passed else FAIL

    @staticmethod
    def value_text(item: EcValue, fmt: str = "{:.2f}") -> str:
        """The value with its unit (``26.12 ‰``, ``1.08 px``), ``n/a`` when not measured."""
        return "n/a" if item.value is None else fmt.format(item.value) + unit_text(item.unit)


def unit_text(unit: str) -> str:
    """A unit as written after a number: ``" ‰"``, ``" px"``, ``"×"`` for ``x``, ``""``."""
    if not unit:
        return ""
    if unit in ("x", "×"):
        return "×"
    return " " + unit


def font_path() -> Path:
    """The TrueType font the annotation writes with: DejaVu Sans as matplotlib (a
    dependency) ships it, so every machine draws the same pixels; it has ‰, °, ×, ≥, ′.
    Found in matplotlib's installed package data without importing matplotlib (0.1 s that
    every process which scores candidates would pay)."""
    spec = importlib.util.find_spec("matplotlib")
    if spec is None or spec.origin is None:
        raise RvmsimError("matplotlib (a dependency of rvmsim) is not installed: its "
                          "DejaVu Sans font draws the annotations")
    return Path(spec.origin).parent / "mpl-data" / "fonts" / "ttf" / "DejaVuSans.ttf"


@functools.lru_cache(maxsize=16)
def font(size_px: int, bold: bool = False) -> ImageFont.FreeTypeFont:
    """DejaVu Sans (Bold) at ``size_px`` px per em (Pillow)."""

    path = font_path()
    if bold:
        path = path.with_name("DejaVuSans-Bold.ttf")
    return ImageFont.truetype(str(path), int(size_px))
