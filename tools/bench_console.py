"""Benchmark of ``rvmsim console``: from a slider move to the updated RVM image (1280×720)
and EC table on the page, in Chromium, through the real page and server.

The console runs as the real command (a child process); Playwright moves the zoom slider
with the mouse.  The latency of a frame is measured in the page, from the input event of
the value it shows to the moment its picture is decoded and its EC table filled.

Two runs:

- ``step``: one move at a time, each waited for (every move's full latency);
- ``drag``: a continuous drag (mouse moves every ``--drag-interval`` ms, not waited for):
  latest value wins, so some values are never rendered; the frames shown are measured.

Usage::

    python tools/bench_console.py [SCENE_OR_RUN] [--moves 60]

Default source: scenes/vehicle_a.yaml (1280×960 sensor, the paper's defaults).
Prints p50/p95/max (ms), the server's own time per step, and the machine.
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
from _console_driver import REPO, chromium_page, console_process, drag_slider, open_console  # noqa: E402


def _pct(values: list[float], q: float) -> float:
    values = sorted(values)
    k = min(len(values) - 1, max(0, round(q * (len(values) - 1))))
    return values[k]


def _line(name: str, ms: list[float]) -> str:
    return (f"{name:>5}: {len(ms):4d} frames  p50 {_pct(ms, 0.5):6.1f} ms  "
            f"p95 {_pct(ms, 0.95):6.1f} ms  max {max(ms):6.1f} ms")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("source", nargs="?", default=str(REPO / "scenes" / "vehicle_a.yaml"))
    ap.add_argument("--moves", type=int, default=60, help="slider moves per run")
    ap.add_argument("--drag-interval", type=float, default=16.0, help="ms between drag moves")
    args = ap.parse_args()
    fractions = [0.2 + 0.6 * ((k * 7) % args.moves) / args.moves for k in range(args.moves)]
    results = {}
    with console_process(Path(args.source).resolve()) as url, chromium_page(1400, 900) as (page, ver):
        open_console(page, url)
        session = page.evaluate("window.rvmConsole.session")
        for mode in ("step", "drag"):
            page.evaluate("window.rvmConsole.timings = []; window.rvmConsole.server = [];"
                          "window.rvmConsole.inputs = 0")
            if mode == "step":
                drag_slider(page, "zoom", fractions, settle=True)
            else:
                sel = "#slider-zoom"
                box = page.locator(sel).bounding_box()
                y = box["y"] + box["height"] / 2
                page.mouse.move(box["x"] + 8 + 0.2 * (box["width"] - 16), y)
                page.mouse.down()
                for k in range(args.moves):
                    f = 0.2 + 0.6 * k / max(1, args.moves - 1)
                    page.mouse.move(box["x"] + 8 + f * (box["width"] - 16), y)
                    time.sleep(args.drag_interval / 1000)
                page.mouse.up()
                drag_slider(page, "zoom", [], settle=True)  # wait for the last frame
            results[mode] = (page.evaluate("window.rvmConsole.timings"),
                             page.evaluate("window.rvmConsole.server"),
                             page.evaluate("window.rvmConsole.inputs"))
    fe = session["fisheye"]
    print(f"rvmsim console benchmark: {session['vehicle']} ({args.source})")
    print(f"fisheye {fe['width']}x{fe['height']} px, RVM picture "
          f"{session['display']['width']}x{session['display']['height']} px (JPEG), ECs at "
          f"{session['ec_output']['width']}x{session['ec_output']['height']} px")
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"Chromium {ver}")
    for mode, (ms, server, inputs) in results.items():
        print(_line(mode, ms) + (f"  ({inputs} inputs)" if mode == "drag" else ""))
        for step in ("ecs", "display", "roi", "page_json", "page_image", "page_table"):
            vals = [s[step] for s in server]
            print(f"         {step:14s} median {statistics.median(vals):6.1f} ms")
    step = results["step"][0]
    print(f"slider move -> picture and EC table, p95 {_pct(step, 0.95):.1f} ms "
          f"({'within' if _pct(step, 0.95) <= 100 else 'over'} the 100 ms target)")


if __name__ == "__main__":
    main()
