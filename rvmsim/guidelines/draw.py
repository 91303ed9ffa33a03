"""Guidelines as pictures: drawn over the RVM colour image (PNG) and as SVG over it.

Convention
----------
Display px, pixel centres at integer coordinates; polylines drawn anti-aliased at 1/16 px.
"""

from __future__ import annotations

import base64
from collections.abc import Sequence

import cv2
import numpy as np

from .overlay import GuidelineSet
from .project import DisplayLine

__all__ = ["draw_lines", "guidelines_svg"]


def draw_lines(rvm_rgb: np.ndarray, lines: Sequence[DisplayLine], width_px: float
               ) -> np.ndarray:
    """A copy of the RVM colour image (H, W, 3) uint8 RGB with ``lines`` drawn in their
    colours, ``width_px`` wide."""
    img = np.ascontiguousarray(rvm_rgb.copy())
    thick = max(1, int(round(width_px)))
    for line in lines:
        colour = tuple(int(round(c * 255)) for c in line.color)
        for piece in line.pieces:
            pts = np.round(piece.uv_px * 16).astype(np.int32).reshape(-1, 1, 2)
            cv2.polylines(img, [pts], False, colour, thick, cv2.LINE_AA, shift=4)
    return img


def _polyline(line: DisplayLine, width_px: float) -> str:
    r, g, b = (int(round(c * 255)) for c in line.color)
    out = []
    for piece in line.pieces:
        pts = " ".join(f"{u:.2f},{v:.2f}" for u, v in piece.uv_px)
        out.append(f'<polyline points="{pts}" fill="none" stroke="rgb({r},{g},{b})" '
                   f'stroke-width="{width_px:g}" stroke-linejoin="round" '
                   f'stroke-linecap="round"/>')
    return "".join(out)


def guidelines_svg(gset: GuidelineSet, rvm_jpeg: bytes | None, *,
                   shown_deg: float = 0.0) -> str:
    """An SVG of the guidelines over the RVM picture (``rvm_jpeg``, embedded; None: lines
    only): the static lines, and one group per steering angle (``id="steer_<deg>"``), only
    ``shown_deg``'s visible (set another group's ``display`` to show it)."""
    w, h = gset.view.output.width, gset.view.output.height
    lw = gset.spec.line_width_px
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
             f'viewBox="-0.5 -0.5 {w} {h}">']
    if rvm_jpeg is not None:
        data = base64.b64encode(rvm_jpeg).decode("ascii")
        parts.append(f'<image x="-0.5" y="-0.5" width="{w}" height="{h}" '
                     f'href="data:image/jpeg;base64,{data}"/>')
    parts.append('<g id="static">' + "".join(_polyline(l, lw) for l in gset.static) + "</g>")
    for deg, group in zip(gset.steering_deg, gset.trajectories):
        hidden = "" if deg == shown_deg else ' display="none"'
        parts.append(f'<g id="steer_{deg:g}"{hidden}>'
                     + "".join(_polyline(l, lw) for l in group) + "</g>")
    parts.append("</svg>")
    return "\n".join(parts) + "\n"
