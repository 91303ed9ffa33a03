"""Draw the EC measurements on the RVM image, the way the paper's Fig. 17–20 show them.

Stripe areas (EC 1-1, 1-2, 1-4) are filled, d (1-3), t_c / t_l / t_r (2-1 … 2-3), the upper
region (2-4), the guideline centres with the image centre line and the 45–55 % band (3-1,
3-2) and the board's box (4-1) are drawn with their values; a panel beside the image lists
every EC with its value, range, score and pass/fail.
"""

from __future__ import annotations

import numpy as np

from .. import labels as L
from .core import EcResult

__all__ = ["annotate"]

PASS = (40, 170, 60)
FAIL = (220, 40, 40)
OFF = (140, 140, 140)
INK = (255, 255, 255)


def _text(img, text, org, scale, color=INK, thick=1):
    import cv2

    x, y = int(org[0]), int(org[1])
    text = text.replace("‰", " o/oo")  # the Hershey fonts have no per-mille sign
    for dx, dy in ((-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, 1)):  # dark outline
        cv2.putText(img, text, (x + dx, y + dy), cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0),
                    thick, cv2.LINE_AA)
    cv2.putText(img, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, scale, color, thick, cv2.LINE_AA)


def _fill(img, mask, color, alpha=0.55):
    if np.any(mask):
        img[mask] = (img[mask] * (1 - alpha) + np.asarray(color) * alpha).astype(np.uint8)


def _status(result: EcResult, ec: str) -> tuple[int, int, int]:
    item = result[ec]
    if not item.enabled:
        return OFF
    return PASS if item.passed else FAIL


def _val(result: EcResult, ec: str, fmt: str = "{:.2f}") -> str:
    v = result[ec].value
    return "n/a" if v is None else fmt.format(v) + result[ec].unit


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
    import cv2

    img = np.ascontiguousarray(rvm_color.copy())
    h, w = rvm_labels.shape
    m = result.measurements
    s = max(0.35, min(w, h) / 900.0)  # text scale
    lw = max(1, int(round(min(w, h) / 400)))

    # 1-1 / 1-2: F and G stripes; the lower patches outlined by their visibility
    for c in "FG":
        _fill(img, rvm_labels == L.object_stripe(c), (255, 0, 255))
        patch = (rvm_labels == L.object_patch(c)).astype(np.uint8)
        _fill(img, patch > 0, (0, 255, 255))
        contours, _ = cv2.findContours(patch, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        colour = PASS if m.patch_visible.get(c) else FAIL
        cv2.drawContours(img, contours, -1, colour, lw)
    # 1-4: B's stripe
    _fill(img, rvm_labels == L.object_stripe("B"), (255, 120, 0))
    # 1-3: d from the top of the image to the highest point of A, B, C
    if m.abc_top_row is not None:
        x = int(np.nonzero(np.isin(rvm_labels[m.abc_top_row],
                                   [L.object_body(c) for c in "ABC"]
                                   + [L.object_stripe(c) for c in "ABC"]))[0].mean())
        cv2.arrowedLine(img, (x, 0), (x, m.abc_top_row), _status(result, "1-3"), lw,
                        tipLength=0.15)
        _text(img, f"d {_val(result, '1-3')}", (x + 6, max(14, m.abc_top_row // 2)), s,
              _status(result, "1-3"))
    # 2-1 … 2-3: bumper heights
    for name, ec in (("t_l", "2-2"), ("t_c", "2-1"), ("t_r", "2-2")):
        xc, top, t = m.bumper_columns[name]
        x = int(round(xc))
        cv2.line(img, (x, h - 1), (x, int(round(top))), _status(result, ec), lw * 2)
        label = f"{name} {t:.1f}px"
        tx = min(max(2, x - int(40 * s)), w - int(120 * s))
        _text(img, label, (tx, max(12, int(top) - 6)), s, _status(result, ec))
    # 2-4: the upper region
    y = m.upper_region_rows
    cv2.line(img, (0, y), (w - 1, y), _status(result, "2-4"), lw)
    _text(img, "2-4 upper region", (4, max(12, y - 4)), s, _status(result, "2-4"))
    # 3-1 / 3-2: guideline centres, image centre, 45–55 % band
    cx = (w - 1) / 2.0
    for yy in range(0, h, max(6, h // 60)):
        cv2.line(img, (int(cx), yy), (int(cx), min(h - 1, yy + max(3, h // 120))), INK, 1)
    for frac in (0.45, 0.55):
        yy = int(round(frac * h))
        for xx in range(0, w, max(6, w // 80)):
            cv2.line(img, (xx, yy), (min(w - 1, xx + max(3, w // 160)), yy), (200, 200, 0), 1)
    if m.guide2_center is not None:
        gx, gy = m.guide2_center
        cv2.drawMarker(img, (int(round(gx)), int(round(gy))), _status(result, "3-1"),
                       cv2.MARKER_CROSS, int(20 * s) + 6, lw)
        _text(img, f"3-1 dx {_val(result, '3-1')}", (int(gx) + 8, int(gy) - 6), s,
              _status(result, "3-1"))
    if m.guide3_center is not None:
        gx, gy = m.guide3_center
        cv2.drawMarker(img, (int(round(gx)), int(round(gy))), _status(result, "3-2"),
                       cv2.MARKER_TILTED_CROSS, int(20 * s) + 6, lw)
        _text(img, f"3-2 y {_val(result, '3-2')}", (int(gx) + 8, int(gy) + int(18 * s)), s,
              _status(result, "3-2"))
    # 4-1: the board's box
    if m.board_box is not None:
        bx, by, bw, bh = m.board_box
        cv2.rectangle(img, (bx, by), (bx + bw - 1, by + bh - 1), _status(result, "4-1"), lw)
        _text(img, f"4-1 w/h {_val(result, '4-1', '{:.3f}')}", (bx, max(12, by - 6)), s,
              _status(result, "4-1"))

    # Results panel
    ts = max(0.45, 0.75 * s)
    row_h = int(32 * ts / 0.45)
    panel_w = int(300 * ts / 0.45)
    rows_needed = len(result.items) + 3
    ph = max(h, rows_needed * row_h + 10)
    out = np.full((ph, w + panel_w, 3), 30, np.uint8)
    out[:h, :w] = img
    _text(out, "EC   value        score", (w + 10, row_h), ts)
    for i, item in enumerate(result.items, start=1):
        colour = OFF if not item.enabled else (PASS if item.passed else FAIL)
        val = "n/a" if item.value is None else f"{item.value:.3f}{item.unit}"
        _text(out, f"{item.id}  {val:<12} {item.score:.3f}", (w + 10, (i + 1) * row_h), ts, colour)
    total_colour = PASS if result.passed else FAIL
    _text(out, f"EC score {result.score:.4g}", (w + 10, (len(result.items) + 2) * row_h + 4),
          ts * 1.1, total_colour, 2)
    return out
