"""Benchmark of ``rvmsim console``: from a slider move to the updated RVM image (1280×720)
and EC table on the page, in Chromium, through the real page and server.

The console runs as the real command (a child process); Playwright moves the zoom slider
with the mouse.  The latency of a frame is measured in the page, from the input event of
the value it shows to the moment its picture is decoded and its EC table filled.

Runs:

- ``step``: one mouse move at a time with the button held, each waited for (every move's
  full latency; the page shows the draft picture while a slider is dragged);
- ``keys``: one arrow-key press at a time, each waited for (the full picture);
- ``drag``: a continuous drag (mouse moves every ``--drag-interval`` ms, not waited for):
  latest value wins, so some values are never rendered; the frames shown are measured;
- ``release``: short drags; from the release (the slider's change event) to the full
  picture;
- ``3 step`` / ``3 keys``: three pages of the same console at once, each moving its slider
  one step at a time (by script: input events as a drag or as keys make them), each
  waited for.

Usage::

    python tools/bench_console.py [SCENE_OR_RUN] [--moves 60] [--only step,drag]

Default source: scenes/vehicle_a.yaml (1280×960 sensor, the paper's defaults).
Prints p50/p95/max (ms), the server's and the page's share, and the machine (with its
load average before and after).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bench_common import cpu_model  # noqa: E402
from _console_driver import (REPO, SETTLED, SETTLED_FULL, chromium_page,  # noqa: E402
                             console_process, drag_slider, open_console)

_RESET = ("window.rvmConsole.timings = []; window.rvmConsole.samples = []; "
          "window.rvmConsole.server = []; window.rvmConsole.inputs = 0")
#: In-page stepping for the three-page runs: move the zoom slider ``n`` times, as a drag
#: (pointerdown first: drafts) or as keys (full pictures), waiting for each frame; ``shift``
#: (a fraction of the range) keeps the pages' values apart (no page reuses another's picture).
_STEPS_JS = """async ([n, drag, shift]) => {
  const s = window.rvmConsole, el = document.getElementById("slider-zoom");
  // waits for the page's "rvm-idle" event (no polling: three pages polling every few ms
  // would load the machine they are measured on); a timer as a fallback
  const done = () => !s.inflight && !s.pending && s.last && s.last.params.zoom === s.current.zoom;
  const settled = () => new Promise((ok) => {
    const f = () => { if (done()) { window.removeEventListener("rvm-idle", f); ok(); } };
    window.addEventListener("rvm-idle", f); setTimeout(function g() { done() ? f() : setTimeout(g, 50); }, 50); });
  const lo = Number(el.min), hi = Number(el.max);
  if (drag) el.dispatchEvent(new PointerEvent("pointerdown", {bubbles: true}));
  for (let k = 0; k < n; k++) {
    el.value = String(lo + (hi - lo) * (0.2 + shift + 0.6 * ((k * 7) % n) / n));
    el.dispatchEvent(new Event("input", {bubbles: true}));
    if (!drag) el.dispatchEvent(new Event("change", {bubbles: true}));
    await settled();
  }
  if (drag) { el.dispatchEvent(new Event("change", {bubbles: true}));
              window.dispatchEvent(new PointerEvent("pointerup")); }
  window.rvmConsoleDone = true;
}"""


def _pct(values: list[float], q: float) -> float:
    values = sorted(values)
    k = min(len(values) - 1, max(0, round(q * (len(values) - 1))))
    return values[k]


def _line(name: str, ms: list[float]) -> str:
    if not ms:
        return f"{name:>8}: no frames"
    return (f"{name:>8}: {len(ms):4d} frames  p50 {_pct(ms, 0.5):6.1f} ms  "
            f"p95 {_pct(ms, 0.95):6.1f} ms  max {max(ms):6.1f} ms")


def _collect(page, draft: bool | None = None) -> tuple[list[float], list[dict], int, list[float]]:
    samples = page.evaluate("window.rvmConsole.samples")
    server = page.evaluate("window.rvmConsole.server")
    if not samples:  # a page without drafts (before they came): every frame is full
        samples = [{"ms": ms, "draft": draft} for ms in page.evaluate("window.rvmConsole.timings")]
    keep = [k for k, s in enumerate(samples) if draft is None or s["draft"] == draft]
    return ([samples[k]["ms"] for k in keep], [server[k] for k in keep],
            page.evaluate("window.rvmConsole.inputs"),
            [samples[k].get("full_ms", samples[k]["ms"]) for k in keep])


def _run_single(page, mode: str, moves: int, interval_ms: float
                ) -> tuple[list[float], list[dict], int, list[float]]:
    page.evaluate(_RESET)
    fractions = [0.2 + 0.6 * ((k * 7) % moves) / moves for k in range(moves)]
    sel = "#slider-zoom"
    if mode == "step":
        drag_slider(page, "zoom", fractions, settle=True)
        return _collect(page, draft=True)
    if mode == "keys":
        page.focus(sel)
        for k in range(moves):
            page.keyboard.press("ArrowRight" if (k // 10) % 2 == 0 else "ArrowLeft")
            page.wait_for_function(SETTLED_FULL, timeout=60000)
        return _collect(page)
    box = page.locator(sel).bounding_box()
    y = box["y"] + box["height"] / 2
    x = lambda f: box["x"] + 8 + f * (box["width"] - 16)  # noqa: E731
    if mode == "drag":
        page.mouse.move(x(0.2), y)
        page.mouse.down()
        for k in range(moves):
            page.mouse.move(x(0.2 + 0.6 * k / max(1, moves - 1)), y)
            time.sleep(interval_ms / 1000)
        page.mouse.up()
        page.wait_for_function(SETTLED_FULL, timeout=60000)
        return _collect(page, draft=True)
    # release: short drags, each ending with the full picture
    for k in range(max(5, moves // 3)):
        a = 0.3 + 0.4 * ((k * 3) % 7) / 7
        page.mouse.move(x(a), y)
        page.mouse.down()
        for j in range(1, 4):
            page.mouse.move(x(a + 0.02 * j), y)
            time.sleep(interval_ms / 1000)
        page.wait_for_function(SETTLED, timeout=60000)
        page.mouse.up()
        page.wait_for_function(SETTLED_FULL, timeout=60000)
    return _collect(page, draft=False)


def _run_three(pages, drag: bool, moves: int
               ) -> tuple[list[float], list[dict], int, list[float]]:
    for p in pages:
        p.evaluate(_RESET + "; window.rvmConsoleDone = false")
    for i, p in enumerate(pages):  # started together, not waited for; values of their own
        p.evaluate(f"(() => {{ ({_STEPS_JS})([{moves}, {str(drag).lower()}, {0.013 * i}]); }})()")
    for p in pages:
        p.wait_for_function("window.rvmConsoleDone === true", timeout=300000)
        p.wait_for_function(SETTLED_FULL, timeout=60000)
    ms: list[float] = []
    server: list[dict] = []
    full: list[float] = []
    inputs = 0
    for p in pages:
        a, b, c, d = _collect(p, draft=True if drag else None)
        ms += a
        server += b
        inputs += c
        full += d
    return ms, server, inputs, full


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source", nargs="?", default=str(REPO / "scenes" / "vehicle_a.yaml"))
    ap.add_argument("--moves", type=int, default=60, help="slider moves per run")
    ap.add_argument("--drag-interval", type=float, default=16.0, help="ms between drag moves")
    ap.add_argument("--only", default="step,keys,drag,release,3 step,3 keys",
                    help="comma-separated runs")
    args = ap.parse_args()
    modes = [m.strip() for m in args.only.split(",") if m.strip()]
    load_before = os.getloadavg()
    results = {}
    with console_process(Path(args.source).resolve()) as url, chromium_page(1400, 900) as (page, ver):
        open_console(page, url)
        session = page.evaluate("window.rvmConsole.session")
        for mode in modes:
            if mode.startswith("3 "):
                ctx = page.context.browser
                pages = [page] + [ctx.new_context(bypass_csp=True,
                                                  viewport={"width": 1400, "height": 900}
                                                  ).new_page() for _ in range(2)]
                for p in pages[1:]:
                    open_console(p, url)
                results[mode] = _run_three(pages, mode == "3 step", args.moves // 2)
                for p in pages[1:]:
                    p.context.close()
            else:
                results[mode] = _run_single(page, mode, args.moves, args.drag_interval)
    load_after = os.getloadavg()
    fe = session["fisheye"]
    print(f"rvmsim console benchmark: {session['vehicle']} ({args.source})")
    print(f"fisheye {fe['width']}x{fe['height']} px, RVM picture "
          f"{session['display']['width']}x{session['display']['height']} px (JPEG), ECs at "
          f"{session['ec_output']['width']}x{session['ec_output']['height']} px")
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"Chromium {ver}; load average (1/5/15 min) before "
          f"{'/'.join(f'{x:.2f}' for x in load_before)}, after "
          f"{'/'.join(f'{x:.2f}' for x in load_after)}")
    print("latency: from the input event to picture and EC table shown (first picture: the "
          "draft or the full one, whichever is ready first); full: to the full picture")
    for mode, (ms, server, inputs, full) in results.items():
        print(_line(mode, ms) + (f"  ({inputs} inputs)" if "drag" in mode or "3" in mode else ""))
        if full != ms:
            print(_line("full", full))
        for step in ("ecs", "pictures", "display", "roi", "render", "page_json", "page_image",
                     "page_table"):
            vals = [s[step] for s in server if step in s]
            if vals:
                print(f"           {step:14s} median {statistics.median(vals):6.1f} ms")
        own = [sum(s.get(k, 0.0) for k in ("ecs", "pictures", "display", "roi")) for s in server]
        if own and ms:
            print(f"           server (evaluation request) median {statistics.median(own):.1f} ms"
                  f" = {100 * statistics.median(own) / statistics.median(ms):.0f} % of the "
                  f"median latency")
    for mode, target in (("step", 100), ("keys", 100), ("drag", 150), ("release", 150),
                         ("3 step", 250), ("3 keys", 250)):
        if mode in results and results[mode][0]:
            p95 = _pct(results[mode][0], 0.95)
            print(f"{mode:>8}: p95 {p95:.1f} ms ({'within' if p95 <= target else 'over'} "
                  f"the {target} ms target)")


if __name__ == "__main__":
    main()
