"""Write docs/img/console.png: a screenshot of the real ``rvmsim console`` page.

Makes a short real tuning run of vehicle A (cmaes-solved, 300 evaluations, in a temporary
folder; the fisheye render comes from the render cache), starts ``rvmsim console`` on it,
opens the page in Debian's Chromium (Playwright), pins candidate 2 as B, and saves the page
(1400 px wide) as an indexed-colour PNG.

Usage::

    python tools/console_screenshot.py [--run RUN] [--out docs/img/console.png]
"""

from __future__ import annotations

import argparse
import io
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _console_driver import REPO, SETTLED, chromium_page, console_process, open_console  # noqa: E402


def _tune(folder: Path) -> Path:
    run = folder / "run"
    subprocess.run([sys.executable, "-m", "rvmsim", "tune", str(REPO / "scenes" / "vehicle_a.yaml"),
                    "--budget", "300", "--workers", "2", "--out", str(run), "--no-progress"],
                   check=True, cwd=folder, stdout=subprocess.DEVNULL,
                   env={**os.environ, "PYTHONPATH": str(REPO)})
    return run


def _small_png(png: bytes) -> bytes:
    """The screenshot as a 256-colour PNG (a fraction of the size, still sharp text)."""
    from PIL import Image

    img = Image.open(io.BytesIO(png)).convert("RGB")
    out = io.BytesIO()
    img.quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(out, "PNG", optimize=True)
    return out.getvalue()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--run", type=Path, default=None, help="a run folder (default: tune one)")
    ap.add_argument("--out", type=Path, default=REPO / "docs" / "img" / "console.png")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="rvmsim-console-shot-") as tmp:
        run = args.run.resolve() if args.run else _tune(Path(tmp)).relative_to(tmp)
        with console_process(run, cwd=Path(tmp)) as url, chromium_page(1400, 900) as (page, _):
            open_console(page, url)
            page.click('#candidates tr[data-rank="2"] button.as-b')
            page.wait_for_function("window.rvmConsole.bResult !== null")
            page.wait_for_function(SETTLED)
            page.wait_for_function("document.getElementById('ab-b').complete")
            png = page.screenshot(full_page=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_bytes(_small_png(png))
    print(f"wrote {args.out} ({args.out.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
