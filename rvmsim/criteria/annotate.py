"""Draw the EC measurements on the RVM image, the way the paper's Fig. 17–20 show them.

Each EC draws its own measurement (:attr:`rvmsim.criteria.EcDefinition.annotate`) on a
:class:`Canvas`, in evaluation order: shapes in RVM px, texts as :class:`Label`\\ s.  Then

1. the picture is scaled to the size a page shows it (small RVM images are enlarged by a
   whole factor to at least :data:`MIN_PICTURE_PX` wide, images wider than the page's column
   :data:`DISPLAY_WIDTH_PX` are reduced to it), so the text is written at the size it is read;
2. the labels are placed without overlap (:func:`place_labels`: the places around their
   point first, else the nearest free place with a leader line) and written with a TrueType
   font (:func:`rvmsim.criteria.canvas.font`) on a dark box in a light tint of their colour,
   which reads on sky and on asphalt;
3. a panel lists every EC (spelled-out name, value with unit, acceptable range, margin,
   pass/fail) and the EC score, beside the picture when it fits in the column, else under
   it; it is exactly as large as its content, so there is no empty strip.

All text is :data:`TEXT_PX` px per em in the returned image, and a page that shows the image
no wider than :data:`DISPLAY_WIDTH_PX` shows it at its own size.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from PIL import Image, ImageDraw

from .canvas import FAIL, INK, OFF, PASS, Canvas, Colour, Label, font, unit_text
from .measure import call_ec
from .registry import EcDefinition, builtin_ecs
from .scoring import EcResult
from .values import EcValue

__all__ = ["annotate", "annotation", "Annotation", "PlacedLabel", "place_labels", "Canvas",
           "Colour", "Label", "PASS", "FAIL", "OFF", "INK", "TEXT_PX", "MIN_TEXT_PX",
           "DISPLAY_WIDTH_PX", "MIN_PICTURE_PX", "panel_rows", "spelled_name",
           "picture_scale", "draw_measurements", "write_labels"]

#: Font size (px per em) of every text of the annotated image, at the size it is made.
TEXT_PX = 14
#: The smallest text (px per em) a page may show of it (the pages show it at ≥ 1:1).
MIN_TEXT_PX = 11
#: The widest a page shows the annotated image (px): the report pages' column.  The image
#: is made at most this wide whenever the panel can go under the picture.
DISPLAY_WIDTH_PX = 1200
#: Smaller RVM images are enlarged by a whole factor to at least this width (px), so labels
#: have room next to what they name.
MIN_PICTURE_PX = 640
#: Gap between a label's box and its point, and padding inside boxes (px).
_GAP, _PAD_X, _PAD_Y = 4, 4, 2
_PANEL_BG: Colour = (32, 32, 32)

Box = tuple[int, int, int, int]


@dataclass(frozen=True)
class PlacedLabel:
    """A label as written: its text, its point and its box ``(x0, y0, x1, y1)`` (px of the
    annotated image, ``x1``/``y1`` exclusive), and whether a leader line joins them."""

    text: str
    at: tuple[float, float]
    box: Box
    leader: bool
    colour: Colour


@dataclass(frozen=True)
class Annotation:
    """The annotated image and where things are in it.

    ``picture`` and ``panel`` are boxes ``(x0, y0, x1, y1)`` (px, exclusive ends);
    ``scale`` = annotated px per RVM px; ``font_px`` the text size (px per em); ``labels``
    the labels placed (inside ``picture``, none overlapping), ``dropped`` the texts that
    found no free place (the panel still lists their ECs)."""

    image: np.ndarray
    picture: Box
    panel: Box
    scale: float
    font_px: int
    labels: tuple[PlacedLabel, ...]
    dropped: tuple[str, ...]


def _definitions(result: EcResult) -> Sequence[EcDefinition | None]:
    if result.definitions:
        return result.definitions
    known = {ec.id: ec for ec in builtin_ecs()}
    return [known.get(i.id) for i in result.items]


def picture_scale(width: int, display_width: int = DISPLAY_WIDTH_PX) -> float:
    """Annotated px per RVM px for an RVM image ``width`` px wide: a whole factor ≥ 1 that
    makes it at least :data:`MIN_PICTURE_PX` wide (and no wider than ``display_width``), or
    ``display_width / width`` for an image wider than the page's column."""
    if width > display_width:
        return display_width / width
    return float(max(1, min(math.ceil(MIN_PICTURE_PX / width), display_width // width)))


def annotate(rvm_color: np.ndarray, rvm_labels: np.ndarray, result: EcResult,
             display_width: int = DISPLAY_WIDTH_PX) -> np.ndarray:
    """The RVM colour image with every EC measurement drawn, plus a results panel.

    Parameters
    ----------
    rvm_color : (H, W, 3) uint8
    rvm_labels : (H, W) uint8
    result : EcResult
        From :func:`rvmsim.criteria.evaluate` on ``rvm_labels``.
    display_width : int
        The widest (px) the page shows the image; see :func:`annotation`.

    Returns
    -------
    (H', W', 3) uint8
        :attr:`Annotation.image`.
    """
    return annotation(rvm_color, rvm_labels, result, display_width).image


def annotation(rvm_color: np.ndarray, rvm_labels: np.ndarray, result: EcResult,
               display_width: int = DISPLAY_WIDTH_PX) -> Annotation:
    """Draw every EC's measurement, place and write the labels, add the panel.

    Parameters
    ----------
    rvm_color : (H, W, 3) uint8
    rvm_labels : (H, W) uint8
    result : EcResult
        From :func:`rvmsim.criteria.evaluate` on ``rvm_labels``.
    display_width : int
        The widest (px) a page shows the image (default: the report column).  The picture
        is scaled by :func:`picture_scale`; the panel goes beside it when both fit in this
        width and the panel is no taller than the picture, else under it.

    Returns
    -------
    Annotation
    """

    h, w = rvm_labels.shape
    canvas = draw_measurements(rvm_color, rvm_labels, result)
    k = picture_scale(w, display_width)
    pw, ph = max(1, round(w * k)), max(1, round(h * k))
    picture = canvas.image if (pw, ph) == (w, h) else cv2.resize(
        canvas.image, (pw, ph), interpolation=cv2.INTER_NEAREST if k > 1 else cv2.INTER_AREA)
    placed, dropped, picture = write_labels(picture, canvas.texts, k, TEXT_PX)

    rows = panel_rows(result, _definitions(result))
    beside = _panel_image(rows, result, TEXT_PX, None)
    if pw + beside.shape[1] <= display_width and beside.shape[0] <= ph:
        panel = np.empty((ph, beside.shape[1], 3), np.uint8)
        panel[:] = _PANEL_BG
        panel[: beside.shape[0]] = beside
        out = np.concatenate([picture, panel], axis=1)
        panel_box = (pw, 0, pw + panel.shape[1], ph)
    else:
        under = _panel_image(rows, result, TEXT_PX, pw)
        out = np.concatenate([picture, under], axis=0)
        panel_box = (0, ph, pw, ph + under.shape[0])
    return Annotation(np.ascontiguousarray(out), (0, 0, pw, ph), panel_box, k, TEXT_PX,
                      tuple(placed), tuple(dropped))


def draw_measurements(rvm_color: np.ndarray, rvm_labels: np.ndarray,
                      result: EcResult) -> Canvas:
    """Every EC of ``result`` draws its measurement on a copy of ``rvm_color`` (RVM px);
    the labels they ask for are in :attr:`Canvas.texts`, not yet written
    (:func:`write_labels`)."""
    h, w = rvm_labels.shape
    canvas = Canvas(np.ascontiguousarray(rvm_color.copy()), rvm_labels,
                    max(0.35, min(w, h) / 900.0), max(1, int(round(min(w, h) / 400))))
    details = result.measurements.details
    for item, ec in zip(result.items, _definitions(result)):
        if ec is not None and ec.annotate is not None:
            call_ec(ec, "annotate", f"the {w}x{h} RVM image", ec.annotate, canvas, item,
                    details.get(item.id))
    return canvas


# ---------------------------------------------------------------------------- labels
def place_labels(sizes: Sequence[tuple[int, int]], points: Sequence[tuple[float, float]],
                 bounds: tuple[int, int], gap: int = _GAP) -> list[Box | None]:
    """Greedy label layout: boxes that overlap neither each other nor any label's point.

    Each label in turn takes the first free place of: the eight places around its point
    (upper right first, then lower right, upper left, lower left, above, below, right,
    left; ``gap`` px from the point, moved inside the bounds), else the free place of a
    grid over the bounds nearest to its point.  Earlier labels win.

    Parameters
    ----------
    sizes : sequence of (w, h)
        Box sizes, px.
    points : sequence of (x, y)
        The point each label belongs to, px.
    bounds : (W, H)
        Boxes stay inside [0, W) × [0, H).
    gap : int
        px between a box and its point.

    Returns
    -------
    list of (x0, y0, x1, y1) or None
        Per label, its box (exclusive ends), or None where no free place is left (or the
        box is larger than the bounds).
    """
    bw, bh = bounds
    keep_out = [(x - 3.0, y - 3.0, x + 4.0, y + 4.0) for x, y in points]
    placed: list[Box] = []
    out: list[Box | None] = []
    for (w, h), (ax, ay) in zip(sizes, points):
        if w > bw or h > bh or w <= 0 or h <= 0:
            out.append(None)
            continue
        blockers = np.array(placed + keep_out, dtype=np.float64).reshape(-1, 4)
        near = np.array([(ax + gap, ay - h - gap), (ax + gap, ay + gap),
                         (ax - w - gap, ay - h - gap), (ax - w - gap, ay + gap),
                         (ax - w / 2, ay - h - gap), (ax - w / 2, ay + gap),
                         (ax + gap, ay - h / 2), (ax - w - gap, ay - h / 2)])
        near = np.round(near)
        near[:, 0] = np.clip(near[:, 0], 0, bw - w)
        near[:, 1] = np.clip(near[:, 1], 0, bh - h)
        box = _first_free(near, w, h, blockers)
        if box is None:
            step = max(2, h // 3)
            xs = np.unique(np.append(np.arange(0, bw - w + 1, step), bw - w))
            ys = np.unique(np.append(np.arange(0, bh - h + 1, step), bh - h))
            gx, gy = np.meshgrid(xs, ys)
            grid = np.stack([gx.ravel(), gy.ravel()], axis=1).astype(np.float64)
            dx = np.maximum(np.maximum(grid[:, 0] - ax, ax - (grid[:, 0] + w)), 0)
            dy = np.maximum(np.maximum(grid[:, 1] - ay, ay - (grid[:, 1] + h)), 0)
            box = _first_free(grid[np.argsort(np.hypot(dx, dy), kind="stable")], w, h,
                              blockers)
        out.append(box)
        if box is not None:
            placed.append(box)
    return out


def _first_free(corners: np.ndarray, w: int, h: int, blockers: np.ndarray) -> Box | None:
    """The first of ``corners`` ((n, 2) top-left px) whose w × h box keeps 1 px from every
    blocker box."""
    if len(corners) == 0:
        return None
    x0, y0 = corners[:, :1], corners[:, 1:2]
    b = blockers.T[None] if len(blockers) else np.zeros((1, 4, 0))
    hit = ((x0 < b[:, 2] + 1) & (b[:, 0] < x0 + w + 1)
           & (y0 < b[:, 3] + 1) & (b[:, 1] < y0 + h + 1))
    free = np.nonzero(~hit.any(axis=1))[0]
    if free.size == 0:
        return None
    x, y = int(corners[free[0], 0]), int(corners[free[0], 1])
    return (x, y, x + w, y + h)


def _tint(colour: Colour) -> Colour:
    """``colour`` mixed with white until it reads on a dark box (luma ≥ 0.6)."""
    c = np.asarray(colour, dtype=np.float64)
    for t in np.linspace(0.0, 1.0, 21):
        mixed = c + (255.0 - c) * t
        if (0.299 * mixed[0] + 0.587 * mixed[1] + 0.114 * mixed[2]) / 255.0 >= 0.6:
            break
    return (int(mixed[0]), int(mixed[1]), int(mixed[2]))


def _text_size(text: str, size_px: int, bold: bool = False) -> tuple[int, int]:
    """(width, height) px of one line: advance width, ascent + descent."""
    f = font(size_px, bold)
    ascent, descent = f.getmetrics()
    return int(math.ceil(f.getlength(text))), ascent + descent


def write_labels(picture: np.ndarray, texts: Sequence[Label], scale: float, size_px: int
                 ) -> tuple[list[PlacedLabel], list[str], np.ndarray]:
    """Place ``texts`` (points in RVM px) on ``picture`` (``scale`` px per RVM px) and
    write them at ``size_px`` px per em: leader lines, then translucent dark boxes edged in
    the label's colour, then the text in a light tint of it.  Returns the labels placed,
    the texts that found no place, and the picture written on."""

    ph, pw = picture.shape[:2]
    points = [((x + 0.5) * scale - 0.5, (y + 0.5) * scale - 0.5) for x, y in
              (t.at for t in texts)]
    sizes = []
    for t in texts:
        tw, th = _text_size(t.text, size_px)
        sizes.append((tw + 2 * _PAD_X, th + 2 * _PAD_Y))
    boxes = place_labels(sizes, points, (pw, ph))
    placed, dropped = [], []
    for t, p, box in zip(texts, points, boxes):
        if box is None:
            dropped.append(t.text)
            continue
        dx = max(box[0] - p[0], 0.0, p[0] - box[2])
        dy = max(box[1] - p[1], 0.0, p[1] - box[3])
        placed.append(PlacedLabel(t.text, p, box, math.hypot(dx, dy) > 2 * _GAP + 1,
                                  t.colour))
    if not placed:
        return placed, dropped, picture
    base = Image.fromarray(np.ascontiguousarray(picture)).convert("RGBA")
    draw = ImageDraw.Draw(base)
    for lab in placed:
        if lab.leader:
            x0, y0, x1, y1 = lab.box
            end = (min(max(lab.at[0], x0), x1 - 1), min(max(lab.at[1], y0), y1 - 1))
            draw.line([lab.at, end], fill=(0, 0, 0, 255), width=3)
            draw.line([lab.at, end], fill=(*_tint(lab.colour), 255), width=1)
            draw.ellipse([lab.at[0] - 2, lab.at[1] - 2, lab.at[0] + 2, lab.at[1] + 2],
                         fill=(*_tint(lab.colour), 255), outline=(0, 0, 0, 255))
    overlay = Image.new("RGBA", base.size, (0, 0, 0, 0))
    odraw = ImageDraw.Draw(overlay)
    for lab in placed:
        x0, y0, x1, y1 = lab.box
        odraw.rectangle([x0, y0, x1 - 1, y1 - 1], fill=(0, 0, 0, 190),
                        outline=(*lab.colour, 255))
    base = Image.alpha_composite(base, overlay)
    draw = ImageDraw.Draw(base)
    f = font(size_px)
    for lab in placed:
        draw.text((lab.box[0] + _PAD_X, lab.box[1] + _PAD_Y), lab.text, font=f,
                  fill=(*_tint(lab.colour), 255), anchor="la")
    return placed, dropped, np.asarray(base.convert("RGB"))


# ---------------------------------------------------------------------------- panel
def _num(x: float) -> str:
    """Four significant digits (whole numbers from 1000 on)."""
    return f"{x:.0f}" if abs(x) >= 1000 else f"{x:.4g}"


def _range_text(item: EcValue, binary: bool) -> str:
    u = unit_text(item.unit)
    lo, hi = item.low, item.high
    if binary:
        return "yes"
    if lo is not None and hi is not None:
        return f"= {_num(lo)}{u}" if lo == hi else f"{_num(lo)} – {_num(hi)}{u}"
    if lo is not None:
        return f"≥ {_num(lo)}{u}"
    if hi is not None:
        return f"≤ {_num(hi)}{u}"
    return "—"


def panel_rows(result: EcResult, definitions: Sequence[EcDefinition | None] | None = None
               ) -> list[tuple[str, str, str, str, str, str]]:
    """The panel's rows, one per EC: id, name (spelled out), value with unit, acceptable
    range, margin (:attr:`EcValue.margin`, signed, with unit) and ``pass``/``fail``/
    ``off``.  Binary ECs read ``yes``/``no`` and have no margin."""
    defs = _definitions(result) if definitions is None else definitions
    rows = []
    for item, ec in zip(result.items, defs):
        binary = ec.binary if ec is not None else item.yes_no
        u = unit_text(item.unit)
        if item.value is None:
            value = "n/a"
        elif binary:
            value = "yes" if item.value >= 0.5 else "no"
        else:
            value = _num(item.value) + u
        m = item.margin
        if binary:  # ✓/✗, as every table shows a yes/no EC (EcValue.margin_text)
            margin = item.check_mark()
        else:
            margin = "—" if m is None else ("+" if m >= 0 else "−") + _num(abs(m)) + u
        result_text = "off" if not item.enabled else ("pass" if item.passed else "fail")
        rows.append((item.id, spelled_name(item.name), value, _range_text(item, binary),
                     margin, result_text))
    return rows


def spelled_name(name: str) -> str:
    """An EC's snake_case name in words: ``_`` as spaces, runs of the scene's object
    letters A–G as letters (``fg`` → ``F, G``, ``b`` → ``B``), ``guideN`` → ``guideline N``
    (``fg_stripe_area_ratio`` → ``F, G stripe area ratio``)."""
    words = []
    for token in name.split("_"):
        if token and set(token) <= set("abcdefg") and list(token) == sorted(set(token)):
            token = ", ".join(token.upper())
        elif re.fullmatch(r"guide\d+", token):
            token = "guideline " + token[5:]
        words.append(token)
    return " ".join(w for w in words if w)


_HEAD = ("EC", "criterion", "value", "limit", "margin", "result")


def _panel_image(rows: Sequence[tuple[str, ...]], result: EcResult, size_px: int,
                 width: int | None) -> np.ndarray:
    """The panel as an RGB image exactly as tall as its text.  With ``width`` (under the
    picture) it is that wide: the rows go in two blocks side by side when they fit, else
    the criterion column is shortened with … to fit."""

    f, fb = font(size_px), font(size_px, True)
    line = _text_size("Ag", size_px)[1] + 4
    gap = max(8, round(0.7 * size_px))  # between columns, and the panel's margin
    cols = [max([_text_size(r[c], size_px)[0] for r in rows]
                + [_text_size(_HEAD[c], size_px, True)[0]]) for c in range(6)]
    block = sum(cols) + gap * 5
    blocks = 2 if width is not None and len(rows) > 4 and 2 * block + 4 * gap <= width else 1
    if width is not None and blocks == 1 and block + 2 * gap > width:
        cols[1] = max(size_px * 4, cols[1] - (block + 2 * gap - width))
        block = sum(cols) + gap * 5
    footer = (f"EC score {result.score:.4g} · "
              + ("all ECs pass" if result.passed else "not all pass"))
    pw = (max(block + 2 * gap, _text_size(footer, size_px, True)[0] + 2 * gap)
          if width is None else width)
    per_block = math.ceil(len(rows) / blocks)
    ph = line * (per_block + 2) + 2 * (size_px // 2) + 4
    img = Image.new("RGB", (pw, ph), _PANEL_BG)
    draw = ImageDraw.Draw(img)
    right = {2, 3, 4}  # numbers right-aligned
    for b in range(blocks):
        xs = [gap + b * (block + 2 * gap)]
        for c in cols[:-1]:
            xs.append(xs[-1] + c + gap)
        y = size_px // 2
        for c, text in enumerate(_HEAD):
            x = xs[c] + cols[c] if c in right else xs[c]
            draw.text((x, y), text, font=fb, fill=(200, 200, 200),
                      anchor="ra" if c in right else "la")
        part = slice(b * per_block, (b + 1) * per_block)
        for item, row in zip(result.items[part], rows[part]):
            y += line
            colour = _tint(Canvas.status(item))
            for c, text in enumerate(row):
                if c == 1:
                    text = _fit(text, cols[1], size_px)
                x = xs[c] + cols[c] if c in right else xs[c]
                draw.text((x, y), text, font=f, fill=colour if c != 1 else (235, 235, 235),
                          anchor="ra" if c in right else "la")
    y = size_px // 2 + line * (per_block + 1) + 4
    draw.text((gap, y), footer, font=fb, fill=_tint(PASS if result.passed else FAIL),
              anchor="la")
    return np.asarray(img)


def _fit(text: str, width: int, size_px: int) -> str:
    """``text``, shortened with … to at most ``width`` px."""
    if _text_size(text, size_px)[0] <= width:
        return text
    while text and _text_size(text + "…", size_px)[0] > width:
        text = text[:-1]
    return text.rstrip() + "…"
