"""What an EC's annotate function draws on (:class:`Canvas`), its colours and outlined text;
on its own so that EC definitions can name it without importing the annotation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .values import EcValue

__all__ = ["Canvas", "Colour", "PASS", "FAIL", "OFF", "INK", "draw_text"]

#: RGB colour.
Colour = tuple[int, int, int]
PASS: Colour = (40, 170, 60)
FAIL: Colour = (220, 40, 40)
OFF: Colour = (140, 140, 140)
INK: Colour = (255, 255, 255)


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
        OpenCV font scale that suits the image size.
    line_width : int
        Line width (px) that suits the image size.

    Convention: pixel centres at integer (column, row), as in the measurements.
    """

    image: np.ndarray
    labels: np.ndarray
    text_scale: float
    line_width: int

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) px."""
        return (int(self.labels.shape[0]), int(self.labels.shape[1]))

    def text(self, text: str, org: tuple[float, float], colour: Colour = INK,
             scale: float | None = None, thick: int = 1) -> None:
        """Outlined text with its baseline starting at ``org`` (px)."""
        draw_text(self.image, text, org, self.text_scale if scale is None else scale, colour,
                  thick)

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
        """The value with its unit, ``n/a`` when it was not measured."""
        return "n/a" if item.value is None else fmt.format(item.value) + item.unit


def draw_text(img: np.ndarray, text: str, org: tuple[float, float], scale: float,
              colour: Colour = INK, thick: int = 1) -> None:
    """Outlined text on an RGB image (the Hershey fonts have no per-mille sign: o/oo)."""
    import cv2

    x, y = int(org[0]), int(org[1])
    text = text.replace("‰", " o/oo")
    for dx, dy in ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, 1)):  # dark outline
        cv2.putText(img, text, (x + dx, y + dy), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0),
                    thick, cv2.LINE_AA)
    cv2.putText(img, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, scale, colour, thick, cv2.LINE_AA)
