"""What the run report says beyond the tuning itself: the tool that made it (version,
commit, date), what "all ECs pass" means (the nominal pose) with the yield when one is known
for the setting, the sign-off sheet (a link, or how to make one), and the picture at the
display's size.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .page import escape, img_tag, url_path
from .provenance import Provenance
from .records import known_yield, signoff_files
from ..isp import params_to_dict
from ..pipeline import rvm_color
from ..tune.summary import signoff_command

if TYPE_CHECKING:
    from ..isp import IspParams, OutputSpec
    from ..render import FisheyeImages

__all__ = ["provenance_line", "yield_note", "signoff_note", "display_figure"]


def provenance_line(p: Provenance) -> str:
    """One muted line: rvmsim version, commit, date (UTC), machine."""
    return (f'<p class="muted" id="tool">Made by rvmsim {escape(p.version)}, commit '
            f"<code>{escape(p.commit_text)}</code>, on {escape(p.date)} "
            f"({escape(p.machine)}, {p.cpu_count} CPUs).</p>")


def _pct(est: dict[str, Any]) -> str:
    lo, hi = (float(v) for v in est.get("ci95", (0.0, 0.0)))
    return (f"{100 * float(est['yield']):.1f} % (95 % CI {100 * lo:.1f}–{100 * hi:.1f} %, "
            f"{est.get('n_pass', '?')} of {est.get('n', '?')} samples)")


def yield_note(run_dir: Path, params: IspParams, nominal_passed: bool, *,
               robust: bool = False) -> str:
    """The yield of ``params`` when a sign-off or robustness result beside the run judged
    exactly them, else a neutral note that the verdict is the nominal one (``robust``: the
    run's own samples give a tuning yield, shown in its robust section)."""

    known = known_yield(run_dir, params_to_dict(params))
    verdict = "all ECs pass" if nominal_passed else "not all ECs pass"
    if known is None:
        own = ("; the robust tuning's yield on its own samples is in the section below"
               if robust else "")
        return (f'<p class="muted" id="yield-note">"{escape(verdict)}" is the verdict at the '
                "nominal pose (the camera exactly as designed, unloaded); the production "
                "yield over mount tolerances and load states is not measured for this "
                f"setting{own} (<code>rvmsim robustness</code>, then <code>rvmsim signoff"
                "</code>).</p>")
    est = known.estimate
    cls = "warn" if float(est["yield"]) < 1.0 else ""
    before = ("" if known.before is None else
              f"; before end-of-line compensation {escape(_pct(known.before))}")
    after = " after end-of-line compensation" if known.before is not None else ""
    return (f'<p class="{cls}" id="yield-note">Production yield{after}: '
            f"<b>{escape(_pct(est))}</b>{before}, over mount tolerances and load states "
            f"(<code>{escape(known.source)}</code>). \"{verdict}\" is the nominal pose's "
            "verdict.</p>")


def signoff_note(run_dir: Path, report_dir: Path) -> str:
    """A link to the run's sign-off sheet (relative to the report's folder), or the
    command that makes one."""
    found = signoff_files(run_dir)
    if found is not None:
        href = url_path(Path(os.path.relpath(found[0], report_dir)).as_posix())
        return (f'<p id="signoff-link">Sign-off sheet: <a href="{escape(href)}">'
                f"{escape(found[0].name)}</a>.</p>")
    cmd = signoff_command(run_dir)
    return (f'<p class="muted" id="signoff-link">No sign-off sheet yet: '
            f"<code>{escape(cmd)}</code> makes one (docs/signoff.md).</p>")


def display_figure(images: FisheyeImages, params: IspParams, record: OutputSpec) -> str:
    """The best candidate's picture at the RVM image of record (the scene's or criteria's
    ``display.rvm_image_px``: what the run writes as ``best/rvm_display.png``), made from
    the images shown, so it always matches them."""

    w, h = record.width, record.height
    picture = rvm_color(images, params, record)
    return (f'<figure id="display">{img_tag(picture, "RVM picture at the display size")}'
            f"<figcaption>The RVM picture at the display's {w} × {h} px (the output of "
            "record; the run writes it as best/rvm_display.png).</figcaption></figure>")
