"""The HTML page kit shared by every rvmsim page (run report, sweep, validation).

Self-contained pages: one stylesheet inline, images as ``data:`` URIs, no scripts or network.
"""

from __future__ import annotations

import base64
import html
import io
from urllib.parse import quote
from typing import TYPE_CHECKING

import cv2
import imageio.v3 as iio
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["CSS", "escape", "url_path", "png_bytes", "shrink", "data_uri", "img_tag", "figure_png", "page",
           "sha_html", "path_html"]

CSS = """
body{font-family:sans-serif;margin:1.5em auto;max-width:1200px;color:#222;padding:0 1em}
h1{margin-bottom:.2em}h2{border-bottom:2px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0}
th,td{border:1px solid #bbb;padding:.25em .6em;text-align:left;vertical-align:top}
th{background:#eee}td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
tr.pass td{background:#d8f0d8}tr.fail td{background:#f6d0d0}tr.off td{background:#e4e4e4;color:#666}
td.pass{background:#d8f0d8}td.fail{background:#f6d0d0}td.off{background:#e4e4e4;color:#666}
tr.tuned td{font-weight:bold}
.badge{display:inline-block;padding:.1em .5em;border-radius:.3em;color:#fff;font-weight:bold}
.badge.pass{background:#2a8a3a}.badge.fail{background:#c02828}
.warn{background:#fff3cd;border:1px solid #e0b84a;padding:.5em .8em}
figure{display:inline-block;margin:.5em 1em .5em 0;vertical-align:top}
figcaption{font-size:.9em;color:#444;max-width:640px}
img{max-width:100%;border:1px solid #999}
.gallery{display:flex;flex-wrap:wrap;gap:1em}
.card{border:1px solid #bbb;border-radius:.4em;padding:.6em;width:340px;background:#fafafa}
.card.rank1{border:2px solid #2a8a3a}
.margins{display:flex;flex-wrap:wrap;gap:.25em;font-size:.85em;margin:.4em 0}
.margins span{padding:.05em .35em;border-radius:.25em;white-space:nowrap}
.margins .pass{background:#d8f0d8}.margins .fail{background:#f6d0d0;color:#8a1010}
code{background:#f0f0f0;padding:.1em .3em;word-break:break-all;overflow-wrap:anywhere;white-space:normal;display:inline-block;max-width:100%}
code.sha,code.path{word-break:normal;overflow-wrap:normal;white-space:nowrap;display:inline}
code.sha{font-size:.8em}code.path{white-space:normal}.ecid,.nobr{white-space:nowrap}
.muted{color:#666;font-size:.9em}
pre{background:#f4f4f4;padding:1em;white-space:pre-wrap}
"""


def escape(value: object) -> str:
    """HTML-escape anything (quotes included)."""
    return html.escape(str(value), quote=True)


def url_path(path: str) -> str:
    """``path`` (a relative file path) quoted for an ``href`` or ``src``: a name that is
    not valid UTF-8 by its bytes (``car\\udcff.png`` → ``car%FF.png``), so the link finds
    the file."""
    return quote(path, errors="surrogateescape")


def sha_html(digest: str | None) -> str:
    """A SHA-256 (or "—") in monospace that never breaks inside it."""
    return f'<code class="sha">{escape(digest or "—")}</code>'


def path_html(path: object) -> str:
    """A file path in monospace that breaks only after a ``/`` (never inside a name)."""
    words = [f'<span class="nobr">{escape(part)}</span>' if part else ""
             for part in str(path).split("/")]
    return '<code class="path">' + "/<wbr>".join(words) + "</code>"


def png_bytes(image: np.ndarray) -> bytes:
    """``image`` ((H, W) or (H, W, 3) uint8) encoded as PNG."""

    return iio.imwrite("<bytes>", np.ascontiguousarray(image), extension=".png")


def shrink(image: np.ndarray, max_px: int) -> np.ndarray:
    """Downscale so the longest side is at most ``max_px`` (never enlarges)."""

    h, w = image.shape[:2]
    f = max_px / max(h, w)
    if f >= 1.0:
        return image
    size = (max(1, round(w * f)), max(1, round(h * f)))
    return cv2.resize(image, size, interpolation=cv2.INTER_AREA)


def data_uri(png: bytes) -> str:
    """PNG bytes as a base64 ``data:`` URI."""
    return "data:image/png;base64," + base64.b64encode(png).decode("ascii")


def img_tag(image: np.ndarray, alt: str, max_px: int | None = None) -> str:
    """An ``<img>`` element embedding ``image`` (shrunk to ``max_px`` on its longest side)."""
    if max_px is not None:
        image = shrink(image, max_px)
    return f'<img src="{data_uri(png_bytes(image))}" alt="{escape(alt)}">'


def figure_png(fig: Figure) -> bytes:
    """A matplotlib figure as PNG bytes (Agg canvas, 100 dpi)."""

    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def page(title: str, body: str) -> str:
    """A whole HTML document: ``title`` and ``body`` (already HTML) with the stylesheet."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{CSS}</style></head>"
            f"<body>{body}</body></html>\n")


