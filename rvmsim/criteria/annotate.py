"""Draw the EC measurements on the RVM image, the way the paper's Fig. 17–20 show them.

Each EC draws its own measurement (:attr:`rvmsim.criteria.EcDefinition.annotate`) on a
:class:`Canvas`, in evaluation order; a panel beside the image then lists every EC with its
value, score and pass/fail, and the EC score.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .canvas import FAIL, INK, OFF, PASS, Canvas, Colour, draw_text
from .registry import EcDefinition, builtin_ecs
from .scoring import EcResult

__all__ = ["annotate", "Canvas", "Colour", "PASS", "FAIL", "OFF", "INK"]

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
