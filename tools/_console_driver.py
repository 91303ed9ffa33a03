"""Shared by tools/bench_console.py and tools/console_screenshot.py: start the real
``rvmsim console`` (a child process on a free loopback port) and open its page in Debian's
Chromium through Playwright."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

REPO = Path(__file__).resolve().parents[1]
CHROMIUM = "/usr/bin/chromium"


@contextmanager
def console_process(source: Path, cwd: Path | None = None) -> Iterator[str]:
    """``rvmsim console SOURCE --port 0 --no-browser`` in a child process; yields its URL,
    and stops it (SIGINT, as Ctrl-C) afterwards."""
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-m", "rvmsim", "console", str(source), "--port",
                             "0", "--no-browser"], cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout is not None and proc.stderr is not None
        line = proc.stdout.readline()
        match = re.search(r"http://\S+", line)
        if match is None:
            raise SystemExit(f"rvmsim console did not start: {line}{proc.stderr.read()}")
        yield match.group(0)
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@contextmanager
def chromium_page(width: int, height: int) -> Iterator[tuple[object, str]]:
    """A Playwright page in Chromium (CSP bypassed so the tool can evaluate its
    expressions) and the browser's version."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            ctx = browser.new_context(bypass_csp=True, viewport={"width": width, "height": height})
            yield ctx.new_page(), browser.version
        finally:
            browser.close()


SETTLED = ("(() => { const s = window.rvmConsole; return s && !s.inflight && !s.pending && "
           "s.last && Object.keys(s.current).every(k => s.last.params[k] === s.current[k]); })()")
#: Settled, and the picture shown is the full one (not a drag's draft).
SETTLED_FULL = SETTLED.replace("s.last &&", "s.last && (!('shown' in s) || (s.shown && "
                                             "!s.shown.draft)) &&")


def open_console(page, url: str) -> None:
    """Load the page and wait for its first frame."""
    page.goto(url)
    page.wait_for_function("window.rvmConsole && window.rvmConsole.frames >= 1", timeout=60000)
    page.wait_for_function(SETTLED_FULL, timeout=60000)


def drag_slider(page, name: str, fractions: list[float], settle: bool) -> None:
    """Drag the slider of parameter ``name`` with the mouse through ``fractions`` of its
    width (one mouse move each); with ``settle``, wait for each value's frame."""
    sel = f"#slider-{name}"
    page.locator(sel).scroll_into_view_if_needed()
    box = page.locator(sel).bounding_box()
    y = box["y"] + box["height"] / 2
    x = lambda f: box["x"] + 8 + f * (box["width"] - 16)  # noqa: E731
    value = page.eval_on_selector(sel, "e => (e.value - e.min) / (e.max - e.min)")
    page.mouse.move(x(value), y)
    page.mouse.down()
    for f in fractions:
        page.mouse.move(x(f), y)
        if settle:
            page.wait_for_function(SETTLED, timeout=60000)
    page.mouse.up()
    page.wait_for_function(SETTLED_FULL, timeout=60000)
