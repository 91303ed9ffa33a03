"""The robustness page of a setting in several markets (``rvmsim robustness --markets``).

The yield over all markets (a car passes when it passes every market) with its 95 %
interval, one row per market (its yield and interval, the limiting EC: the one that fails
most often there), the setting and input files, the tolerances and the all-markets yield
per load state; then per market what the one-market page shows (ECs over the samples,
margins, yield curve, nominal and worst sample).  Every string from a user's files is
HTML-escaped.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

from .page import data_uri, escape, page
from .provenance import FileRecord, file_record, files_table, scene_records
from .robustness import (RobustnessInputs, _ec_rows, _picture, _sample_text,
                         margin_histograms_png, write_json_and_page, yield_curve_png)
from .setting import SettingRecord, by_load_html, setting_html, variation_html

if TYPE_CHECKING:
    from ..robust import MarketsRobustness, MarketYield

__all__ = ["markets_robustness_page", "write_markets_robustness_outputs"]


def _anchor(name: str) -> str:
    return "market-" + (re.sub(r"[^A-Za-z0-9_-]+", "-", name).strip("-") or "x")


def _ci_cell(yield_: float, ci: tuple[float, float], n_pass: int, n: int) -> str:
    return (f'<td class="num">{100 * yield_:.1f} %</td><td class="num">{100 * ci[0]:.1f}–'
            f'{100 * ci[1]:.1f} %</td><td class="num">{n_pass} of {n}</td>')


def _market_row(m: MarketYield) -> str:
    """One row of the markets table."""
    r, b = m.result, m.limiting
    est = r.estimate
    bind = "no EC fails" if b is None else (
        f"{escape(b.id)} {escape(b.name)}: fails on {100 * b.failure_rate:.1f} % (worst "
        f"{'—' if b.worst_value is None else f'{b.worst_value:.3g}'} {escape(b.unit)})")
    nominal = "—" if r.nominal is None else ("pass" if r.nominal.ec.passed else "FAIL")
    cls = "pass" if est.n_pass == est.n else "fail"
    return (f'<tr class="{cls} market"><td><a href="#{_anchor(m.name)}">{escape(m.name)}</a>'
            f'</td><td>{escape(m.title)}</td><td>{escape(r.criteria_name)}</td>'
            f'{_ci_cell(est.yield_, est.ci, est.n_pass, est.n)}<td>{bind}</td>'
            f'<td>{nominal}</td></tr>')


def _market_section(m: MarketYield) -> str:
    """What the one-market page shows, for this market."""
    r = m.result
    if r.nominal is None or r.worst is None:
        raise ValueError("the robustness page needs the nominal and worst frames "
                         "(markets_robustness(..., frames=True))")
    hist, curve = data_uri(margin_histograms_png(r.ecs)), data_uri(yield_curve_png(r))
    return f"""
<h2 id="{_anchor(m.name)}">{escape(m.name)}: {escape(m.title)}</h2>
<p>Site {escape(m.site)}, criteria {escape(r.criteria_name)}: yield <b>{100 * r.yield_:.1f} %</b>
({r.estimate.n_pass} of {r.estimate.n} samples pass every enabled EC of this market).</p>
<table><tr><th>EC</th><th>measurement</th><th>range</th><th>fails</th><th>worst value</th>
<th>worst margin</th><th>what drives it</th></tr>{_ec_rows(r)}</table>
<figure><img src="{hist}" alt="margin histograms, {escape(m.name)}"><figcaption>Margin of
each sample per EC (below 0 fails).</figcaption></figure>
<figure><img src="{curve}" alt="yield curve, {escape(m.name)}"><figcaption>This market's yield
against the tolerance scale factor.</figcaption></figure>
<div class="gallery"><figure>{_picture(r.nominal, f"nominal, {m.name}")}
<figcaption>Nominal (as designed)</figcaption></figure>
<figure>{_picture(r.worst, f"worst sample, {m.name}")}
<figcaption>Worst: {escape(_sample_text(r))}</figcaption></figure></div>"""


def markets_robustness_page(result: MarketsRobustness, setting: SettingRecord,
                            records: list[FileRecord]) -> str:
    """The whole HTML document for ``result``."""
    est = result.estimate
    ok = result.meets_min_yield
    badge = "" if result.min_yield is None else (
        f' <span class="badge {"pass" if ok else "fail"}">{"meets" if ok else "below"} '
        f"--min-yield {100 * result.min_yield:g} %</span>")
    names = ", ".join(m.name for m in result.markets)
    return page(f"Robustness: {result.scene_name} in {len(result.markets)} markets", f"""
<h1>Robustness of {escape(result.scene_name)} in {len(result.markets)} markets</h1>
<p>Yield over all markets ({escape(names)}) <b>{100 * est.yield_:.1f} %</b> (95 % Wilson
interval {100 * est.ci[0]:.1f}–{100 * est.ci[1]:.1f} %): {est.n_pass} of {est.n} samples pass
every enabled EC of every market{badge}. Each sample is judged at each market's site with
its criteria. Variation: {escape(result.variation.source)}; seed {result.seed}.</p>
<h2 id="markets">Yield per market</h2>
<table><tr><th>market</th><th>title</th><th>criteria</th><th>yield</th><th>95 % interval</th>
<th>samples passing</th><th>limiting EC (fails most often)</th><th>nominal car</th></tr>
{"".join(_market_row(m) for m in result.markets)}
<tr class="{"pass" if est.n_pass == est.n else "fail"} all-markets"><td><b>all markets</b></td>
<td>passes every market</td><td></td>{_ci_cell(est.yield_, est.ci, est.n_pass, est.n)}
<td></td><td></td></tr></table>
<h2 id="setting">The setting judged</h2>{setting_html(setting)}
<h2 id="inputs">Input files</h2>{files_table(records)}
<h2 id="tolerances">Tolerances and load states</h2>
{variation_html(result.variation.as_dict())}
<h3>Yield over all markets per load state</h3>{by_load_html(result.as_dict()["yield_by_load"])}
{"".join(_market_section(m) for m in result.markets)}
<pre>{escape(result.summary())}</pre>
""")


def _records(result: MarketsRobustness, setting: SettingRecord,
             inputs: RobustnessInputs) -> list[FileRecord]:
    """The setting, the scene and its meshes, each market's site and criteria files, the
    variation file."""
    records = [setting.file, *scene_records(result.scene_file)]
    for m in result.markets:
        for role, src in (("site", m.site), ("criteria", m.criteria)):
            if src is not None and src.lower().endswith((".yaml", ".yml")):
                records.append(file_record(f"{role} ({m.name})", src))
    if inputs.variation_file is not None:
        records.append(file_record("variation", inputs.variation_file))
    return records


def write_markets_robustness_outputs(result: MarketsRobustness, out_dir: str | Path,
                                     inputs: RobustnessInputs | None = None) -> list[Path]:
    """Write ``robustness.json`` (:meth:`~rvmsim.robust.MarketsRobustness.as_dict`, with
    ``inputs`` as :func:`~rvmsim.report.write_robustness_outputs` records them) and
    ``robustness.html`` into ``out_dir``.

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    how = inputs or RobustnessInputs()
    return write_json_and_page(
        result, out_dir, how, lambda setting: _records(result, setting, how),
        lambda setting, records: markets_robustness_page(result, setting, records),
        {"criteria_file": None, "compensation": None,
         "markets": how.markets or ",".join(m.name for m in result.markets)})
