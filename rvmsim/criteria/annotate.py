"""Draw the EC measurements on the RVM image, the way the paper's Fig. 17–20 show them.

Each EC draws its own measurement (:attr:`rvmsim.criteria.EcDefinition.annotate`) on a
:class:`Canvas`, in evaluation order; a panel beside the image then lists every EC with its
value, score and pass/fail, and the EC score.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .registry import EcDefinition, builtin_ecs
from .scoring import EcResult, EcValue

__all__ = ["annotate", "Canvas", "Colour", "PASS", "FAIL", "OFF", "INK"]

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


def _definitions(result: EcResult) -> Sequence[EcDefinition | None]:
    if result.definitions:
        return result.definitions
    known = {ec.id: ec for ec in builtin_ecs()}
    return [known.get(i.id) for i in result.items]


def annotate(rvm_color: np.ndarray, rvm_labels: np.ndarray, result: EcResult) -> np.ndarray:
    """The RVM colour image with every EC measurement drawn, plus a results panel.

    Parameters
    ----------
    rvm_color : (H, W, 3) uint8
    rvm_labels : (H, W) uint8
    result : EcResult
        From :func:`rvmsim.criteria.evaluate` on ``rvm_labels``.

    Returns
    -------
    (H', W + panel, 3) uint8
        H' ≥ H (the panel may need more rows than a small image has).
    """
    h, w = rvm_labels.shape
    s = max(0.35, min(w, h) / 900.0)  # text scale
    canvas = Canvas(np.ascontiguousarray(rvm_color.copy()), rvm_labels, s,
                    max(1, int(round(min(w, h) / 400))))
    details = result.measurements.details
    for item, ec in zip(result.items, _definitions(result)):
        if ec is not None and ec.annotate is not None:
            ec.annotate(canvas, item, details.get(item.id))
    return _with_panel(canvas.image, result, s)


def _with_panel(img: np.ndarray, result: EcResult, s: float) -> np.ndarray:
    import cv2

    h, w = img.shape[:2]
    ts = max(0.45, 0.75 * s)
    row_h = int(32 * ts / 0.45)
    rows = []
    for item in result.items:
        val = "n/a" if item.value is None else f"{item.value:.3f}{item.unit}"
        rows.append(f"{item.id}  {val:<12} {item.score:.3f}")
    widest = max((cv2.getTextSize(r.replace("‰", " o/oo"), cv2.FONT_HERSHEY_SIMPLEX, ts, 1)[0][0]
                  for r in rows), default=0)
    panel_w = max(int(300 * ts / 0.45), widest + 20)  # long plugin EC ids widen the panel
    rows_needed = len(result.items) + 3
    ph = max(h, rows_needed * row_h + 10)
    out = np.full((ph, w + panel_w, 3), 30, np.uint8)
    out[:h, :w] = img
    draw_text(out, "EC   value        score", (w + 10, row_h), ts)
    for i, (item, text) in enumerate(zip(result.items, rows), start=1):
        draw_text(out, text, (w + 10, (i + 1) * row_h), ts, Canvas.status(item))
    total_colour = PASS if result.passed else FAIL
    draw_text(out, f"EC score {result.score:.4g}", (w + 10, (len(result.items) + 2) * row_h + 4),
              ts * 1.1, total_colour, 2)
    return out
