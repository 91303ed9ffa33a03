"""Printing a page to PDF: headless Chromium (Debian's ``chromium``) driven by Playwright, A4
with a running header and page numbers."""

from __future__ import annotations

import shutil
from pathlib import Path

from .._optional import import_playwright_sync_api
from ..errors import RvmsimError
from .page import escape

__all__ = ["find_chromium", "print_pdf"]


def find_chromium() -> str | None:
    """The Chromium binary (Debian's ``chromium`` first), None when there is none."""
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        if path := shutil.which(name):
            return path
    return None


#: The PDF's running header and footer (Chromium's print templates: their own styles, the
#: ``pageNumber``/``totalPages`` spans filled in by Chromium).
_HEADER = ('<div style="font:8pt sans-serif;width:100%;margin:0 12mm;color:#444;'
           'display:flex;justify-content:space-between"><span>{left}</span>'
           '<span style="font-family:monospace">{right}</span></div>')
_FOOTER = ('<div style="font:8pt sans-serif;width:100%;margin:0 12mm;color:#444;'
           'text-align:right">page <span class="pageNumber"></span> of '
           '<span class="totalPages"></span></div>')


def print_pdf(html: Path, pdf: Path, browser: str, header: tuple[str, str] = ("", "")
              ) -> Path:
    """Print ``html`` to ``pdf`` (A4, backgrounds) with headless Chromium at ``browser``,
    driven by Playwright; the browser is closed before this returns.  Every page carries
    ``header`` (left and right text: the vehicle; the setting's hash and the date) at the
    top and "page N of M" at the bottom.

    Raises
    ------
    RvmsimError
        Chromium did not start or print (one line).
    """
    sync_api = import_playwright_sync_api()
    try:
        with sync_api.sync_playwright() as p:
            b = p.chromium.launch(executable_path=browser, args=["--no-sandbox"])
            try:
                page = b.new_page()
                page.goto(html.resolve().as_uri(), wait_until="load")
                page.pdf(path=str(pdf), format="A4", print_background=True,
                         display_header_footer=True,
                         header_template=_HEADER.format(left=escape(header[0]),
                                                        right=escape(header[1])),
                         footer_template=_FOOTER,
                         margin={"top": "18mm", "bottom": "16mm", "left": "12mm",
                                 "right": "12mm"})
            finally:
                b.close()
    except sync_api.Error as err:
        first = (str(err).strip().splitlines() or ["failed"])[0]
        raise RvmsimError(f"{pdf}: Chromium ({browser}) could not print the PDF: "
                          f"{first}") from None
    return pdf
