"""The robustness page: one self-contained HTML page for an ISP setting's yield over
production variation (``rvmsim robustness``).

Yield with its 95 % interval, a table per EC (failure rate, worst value and margin, its
value as a fitted formula of the offsets and load, and the axis whose terciles differ
most), per-EC margin histograms, the yield against the tolerance scale factor, and the
worst sample's annotated RVM image next to the nominal one (PNG data URIs, built with the
page kit :mod:`.page`).  Every string from a user's files is HTML-escaped.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np
import yaml
from matplotlib.figure import Figure

from ..criteria import bundled_criteria_text
from ..errors import RvmsimError
from ..isp import params_to_dict
from ..robust import EcStats, MarketsRobustness, RobustnessResult
from ..storage import json_default, staged_folder, write_text
from .page import data_uri, escape, figure_png, img_tag, page
from .provenance import FileRecord, file_record, files_table, scene_records
from .setting import (SettingRecord, by_load_html, setting_html, variation_html,
                      worst_margin_text)

if TYPE_CHECKING:
    from ..pipeline import RvmFrame

__all__ = ["robustness_page", "write_robustness_outputs", "margin_histograms_png",
           "yield_curve_png", "RobustnessInputs", "SETTING_FILE"]

#: The params file written beside robustness.json when the setting came from no file.
SETTING_FILE = "setting.yaml"


@dataclass(frozen=True)
class RobustnessInputs:
    """The files a robustness run read, as the command line gave them (None: the scene's
    own section or the built-in default); recorded in robustness.json (``inputs``), shown
    on the page and used to write the commands that reproduce a sample.

    ``compensation`` is a file or ``"default"``; ``render_scale`` is ``--scale``;
    ``markets`` is ``--markets`` (None: one market, the criteria's)."""

    params_file: Path | None = None
    criteria_file: Path | None = None
    variation_file: Path | None = None
    compensation: str | None = None
    render_scale: float = 1.0
    markets: str | None = None

#: Longest side of an embedded RVM image without its ECs drawn, px.  The annotated image is
#: embedded at its own size: :func:`rvmsim.criteria.annotate` makes it as wide as the page
#: shows it, so its text keeps its size (≥ 11 px) on the page.
PICTURE_MAX_PX = 640


def _picture(frame: RvmFrame, alt: str) -> str:
    """``frame``'s annotated image at its own size, else its RVM image."""
    if frame.annotated is not None:
        return img_tag(frame.annotated, alt)
    return img_tag(frame.color, alt, PICTURE_MAX_PX)


def margin_histograms_png(ecs: tuple[EcStats, ...]) -> bytes:
    """One small histogram per enabled EC with a range: the samples' margins (EC unit; the
    red line is the range's edge, left of it fails)."""

    shown = [e for e in ecs if e.enabled and np.isfinite(np.asarray(e.margins)).any()]
    cols = 4
    rows = max(1, math.ceil(len(shown) / cols))
    fig = Figure(figsize=(3.2 * cols, 2.4 * rows))
    for k, e in enumerate(shown):
        ax = fig.add_subplot(rows, cols, k + 1)
        m = np.asarray(e.margins)
        m = m[np.isfinite(m)]
        ax.hist(m, bins=30, color="C3" if e.n_fail else "C0")
        ax.axvline(0.0, color="red", lw=1)
        ax.set_title(f"EC {e.id}: {100 * e.failure_rate:.0f} % fail", fontsize=9)
        ax.set_xlabel(f"margin ({e.unit})" if e.unit else "margin", fontsize=8)
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    return figure_png(fig)


def yield_curve_png(result: RobustnessResult) -> bytes:
    """Yield (with its 95 % interval) against the tolerance scale factor."""

    pts = result.scale_curve
    s = np.array([p.scale for p in pts])
    y = np.array([p.estimate.yield_ for p in pts]) * 100
    lo = np.array([p.estimate.ci[0] for p in pts]) * 100
    hi = np.array([p.estimate.ci[1] for p in pts]) * 100
    fig = Figure(figsize=(5.6, 3.4))
    ax = fig.add_subplot()
    ax.fill_between(s, lo, hi, color="C0", alpha=0.2, label="95 % interval")
    ax.plot(s, y, "o-", color="C0", label="yield")
    if result.min_yield is not None:
        ax.axhline(100 * result.min_yield, color="red", lw=1, ls="--", label="--min-yield")
    ax.set_xlabel("tolerance scale factor")
    ax.set_ylabel("yield (%)")
    ax.set_ylim(-2, 102)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    return figure_png(fig)


def _ec_rows(result: RobustnessResult) -> str:
    rows = []
    for e in result.ecs:
        cls = "off" if not e.enabled else ("fail" if e.n_fail else "pass")
        why = _why(e, result.estimate.n)
        rng = f"[{'–' if e.low is None else f'{e.low:g}'}, {'–' if e.high is None else f'{e.high:g}'}]"
        rows.append(
            f'<tr class="{cls}"><td class="ecid">{escape(e.id)}</td><td>{escape(e.name)}</td>'
            f'<td class="num">{rng} {escape(e.unit)}</td>'
            f'<td class="num">{100 * e.failure_rate:.1f} %</td>'
            f'<td class="num">{"—" if e.worst_value is None else f"{e.worst_value:.3g}"}</td>'
            f'<td class="num">{escape(worst_margin_text(e.low, e.high, e.n_fail, e.worst_margin))}'
            "</td>"
            f'<td>{why}</td></tr>')
    return "".join(rows)


def compensation_values_png(result: RobustnessResult) -> bytes:
    """Histograms of the per-car offsets the EOL step wrote (one per written parameter; the
    red lines are the allowed range)."""

    comp = result.compensated
    assert comp is not None
    names = list(comp.corrections[0].offsets) if comp.corrections else []
    fig = Figure(figsize=(3.4 * max(1, len(names)), 2.6))
    for k, name in enumerate(names):
        ax = fig.add_subplot(1, max(1, len(names)), k + 1)
        ax.hist([c.offsets[name] for c in comp.corrections], bins=30, color="C0")
        for edge in comp.model.range_of(name):
            if math.isfinite(edge) and not (name == "h_pan" and edge == 0):
                ax.axvline(edge, color="red", lw=1)
        ax.set_title("pan turn (°)" if name == "h_pan" else name, fontsize=9)
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    return figure_png(fig)


def _pct(est: dict[str, Any]) -> str:
    """A yield estimate's dict (:meth:`~rvmsim.robust.YieldEstimate.as_dict`) as a cell."""
    lo, hi = (float(v) for v in est["ci95"])
    return (f'{100 * float(est["yield"]):.1f} % <small>({100 * lo:.1f}–{100 * hi:.1f} %, '
            f'n {est["n"]})</small>')


def _compensation_section(result: RobustnessResult) -> str:
    """Before and after end-of-line compensation, side by side ("" without it)."""
    comp, before = result.compensated, result.before_estimate
    if comp is None or before is None or result.before is None:
        return ""
    by_before, by_after = result.yield_by_load(before=True), result.yield_by_load()
    rows = [f'<tr><td><b>every car</b></td><td class="num">{_pct(before.as_dict())}</td>'
            f'<td class="num">{_pct(result.estimate.as_dict())}</td></tr>']
    rows += [f'<tr><td>load: {escape(name)}</td><td class="num">{_pct(by_before[name])}</td>'
             f'<td class="num">{_pct(by_after[name])}</td></tr>' for name in by_after]
    rows += [f'<tr><td>EC {escape(b.id)} fails</td><td class="num">{100 * b.failure_rate:.1f} %'
             f'</td><td class="num">{100 * a.failure_rate:.1f} %</td></tr>'
             for b, a in zip(result.ecs_before, result.ecs) if a.enabled
             and (a.n_fail or b.n_fail)]
    n_out = int((~comp.within_range).sum())
    if n_out:
        first = next(c for c in comp.corrections if c.exceeded)
        rows.append(f'<tr class="fail"><td>EOL range exceeded</td><td></td><td class="num">'
                    f'{n_out} cars (e.g. {escape(first.exceeded[0])})</td></tr>')
    rows += _station_rows(result)
    m = comp.model
    values = data_uri(compensation_values_png(result))
    how = (f"so that every EC passes on the car's picture with the largest margin its budget "
           f"of {m.budget} EC evaluations finds (law ec-solve, from the values that keep "
           f"{result.reference_points} reference ground points where the nominal car shows "
           "them)" if m.law == "ec-solve" else
           f"so that {result.reference_points} reference ground points land where the "
           "nominal car shows them (law reference-points)")
    return f"""
<h2>End-of-line compensation: before and after</h2>
<p>Each car's camera deviation is measured at the end of the line (station σ
{m.angle_sigma_deg:g}° and {m.position_sigma_mm:g} mm per axis, the body's edge on the
capture {m.edge_sigma_px:g} px: assumptions, in load state
{escape(m.measured_at or result.variation.load_states[0].name)}) and the EOL step writes
{escape(", ".join(m.params))} {how}. A car whose margin is inside the station's uncertainty
is marginal ({"failed" if m.marginal == "fail" else "accepted"} by the station's policy).
Model: {escape(m.source)}.</p>
<table><tr><th></th><th>before compensation</th><th>after compensation</th></tr>
{"".join(rows)}</table>
<figure><img src="{values}" alt="per-car values"><figcaption>Per-car offsets from the
platform setting (red: the allowed range).</figcaption></figure>"""


def _three(d: dict[str, Any]) -> str:
    """A ``median``/``p99``/``max`` dict as one cell's text (— where not counted)."""
    return " / ".join("—" if d[k] is None else f"{d[k]:.2f}" for k in ("median", "p99", "max"))


def _guidelines_section(result: RobustnessResult) -> str:
    """How far the guidelines land from where they claim after the EOL step, per line over
    the fleet ("" without compensation or without the car's running gear)."""
    g = result.guidelines
    if g is None:
        return ""
    doc = g.as_dict()
    eol, plat = doc["eol_table"], doc["platform_table"]
    rows = "".join(
        f'<tr><td>{escape(name)}</td>'
        f'<td class="num">{_three(eol["in_field"][name]["px"])}</td>'
        f'<td class="num">{_three(eol["in_field"][name]["cm"])}</td>'
        f'<td class="num">{_three(eol["at_station"][name]["cm"])}</td>'
        f'<td class="num">{_three(plat["in_field"][name]["cm"])}</td></tr>'
        for name in doc["groups"])
    angles = "; ".join(f"{escape(k)}: {', '.join(f'{a:g}' for a in v)}°"
                       for k, v in doc["steering_deg"].items())
    return f"""
<h2>Parking guidelines after the EOL step</h2>
<p>Each car's guideline table is drawn from the pose the station measured and its per-car
values (as <code>rvmsim eol</code> writes it), and looked at through its true pose with the
same values. Per car, a line's error is its largest over its points: on the display, px
between where the line is drawn and where its ground point shows; on the ground, cm between
the ground under the drawn line and where it claims. Over the cars: median / 99th percentile
/ worst. In the field: each car in its own load state; at the station: in the station's
(its error alone). The platform table (design pose, platform setting) for comparison.
Steering-wheel angles: {angles}.</p>
<table><tr><th>line</th><th>EOL table, in the field: px</th><th>in the field: cm</th>
<th>at the station: cm</th><th>platform table, in the field: cm</th></tr>
{rows}</table>"""


def _station_rows(result: RobustnessResult) -> list[str]:
    """The station's verdicts that keep cars from the yield: infeasible (named apart),
    marginal, and cars it let go that fail in the field."""
    comp = result.compensated
    assert comp is not None
    rows = []
    infeasible = [s for s in comp.solutions if s.status == "infeasible"]
    if infeasible:
        rows.append(f'<tr class="fail"><td>infeasible cars: no per-car setting in the '
                    f'allowed ranges passes</td><td></td><td class="num">{len(infeasible)} '
                    f'(e.g. {escape(infeasible[0].reasons[0])})</td></tr>')
    marginal = comp.count("marginal")
    if marginal:
        rows.append(f'<tr><td>marginal cars (a margin inside the station\'s uncertainty)'
                    f'</td><td></td><td class="num">{marginal}</td></tr>')
    escaped = int((comp.accepted & ~result.evaluation.all_passed).sum())
    if escaped:
        rows.append(f'<tr class="fail"><td>passed by the station, failing in the field</td>'
                    f'<td></td><td class="num">{escaped}</td></tr>')
    return rows


def _why(e: EcStats, n: int) -> str:
    """The EC's sensitivity fit (when it fails, or the fit explains it), then its failure
    rate per tercile of the strongest axis in small print."""
    d = e.driver
    terciles = escape(d.describe()) if d is not None else (
        "every sample fails" if e.n_fail and e.n_fail == n else "")
    s = e.sensitivity
    fit = "" if s is None or not (e.n_fail or s.good) else escape(s.describe())
    if fit and terciles:
        return f'{fit}<br><small>terciles: {terciles}</small>'
    return fit or terciles


def _sample_text(result: RobustnessResult) -> str:
    s = result.samples[result.worst_index]
    parts = [f"{n} {v:+.3g}" for n, v in zip(("x", "y", "z"), s.position_mm)]
    parts += [f"{n} {v:+.3g}°" for n, v in zip(("yaw", "pitch", "roll"), s.angles_deg)]
    text = f"sample {s.index}: {', '.join(parts)} (mm, degrees), load {s.load.name}"
    if result.compensated is not None:
        c = result.compensated.corrections[result.worst_index]
        text += "; per-car " + ", ".join(f"{n} {v:.3g}" for n, v in c.values.items())
        text += "".join(f"; {e}" for e in c.exceeded)
    return text


def _input_records(result: RobustnessResult, inputs: RobustnessInputs,
                   setting: SettingRecord) -> list[FileRecord]:
    """Every file the run read: params, scene and meshes, criteria, variation, compensation."""

    records = [setting.file, *scene_records(result.scene_file)]
    crit = inputs.criteria_file
    if crit is not None:
        records.append(FileRecord("criteria", str(crit), None, "bundled criteria set")
                       if bundled_criteria_text(str(crit)) is not None
                       else file_record("criteria", crit))
    if inputs.variation_file is not None:
        records.append(file_record("variation", inputs.variation_file))
    if inputs.compensation is not None:
        records.append(FileRecord("compensation", "default", None, "built-in default model")
                       if inputs.compensation == "default"
                       else file_record("compensation", inputs.compensation))
    return records


def _setting_section(setting: SettingRecord | None, records: list[FileRecord],
                     result: RobustnessResult) -> str:
    """The setting judged, the files read, the tolerances and load states, the yield per
    load state."""
    by_load = "" if result.compensated is not None else (
        "<h3>Yield per load state</h3>" + by_load_html(result.yield_by_load()))
    judged = "" if setting is None else (
        f'<h2 id="setting">The setting judged</h2>{setting_html(setting)}'
        f'<h2 id="inputs">Input files</h2>{files_table(records)}')
    return (f'{judged}<h2 id="tolerances">Tolerances and load states</h2>'
            f"{variation_html(result.variation.as_dict())}{by_load}")


def robustness_page(result: RobustnessResult, setting: SettingRecord | None = None,
                    records: list[FileRecord] | None = None) -> str:
    """The whole HTML document for ``result``; given the ``setting`` (its file and hash)
    and the input ``records``, also those, the tolerance figures and the load states."""
    lo, hi = result.ci
    ok = result.meets_min_yield
    badge = "" if result.min_yield is None else (
        f' <span class="badge {"pass" if ok else "fail"}">{"meets" if ok else "below"} '
        f"--min-yield {100 * result.min_yield:g} %</span>")
    hist = data_uri(margin_histograms_png(result.ecs))
    curve = data_uri(yield_curve_png(result))
    if result.nominal is None or result.worst is None:
        raise ValueError("the robustness page needs the nominal and worst frames "
                         "(robustness(..., frames=True))")
    nominal = "PASS" if result.nominal.ec.passed else "FAIL"
    return page(f"Robustness: {result.scene_name}", f"""
<h1>Robustness of {escape(result.scene_name)}</h1>
<p>Yield{"" if result.compensated is None else " after end-of-line compensation"} <b>{100 * result.yield_:.1f} %</b> (95 % Wilson interval {100 * lo:.1f}–{100 * hi:.1f} %):
{result.estimate.n_pass} of {result.estimate.n} samples pass every enabled EC{badge}.
Criteria: {escape(result.criteria_name)}. Variation: {escape(result.variation.source)};
seed {result.seed}. The nominal car: {nominal} (EC score {result.nominal.ec.score:.3g}).</p>
{_setting_section(setting, records or [], result)}
{_compensation_section(result)}
{_guidelines_section(result)}
<h2>Evaluation criteria over the samples{"" if result.compensated is None else " (after compensation)"}</h2>
<table><tr><th>EC</th><th>measurement</th><th>range</th><th>fails</th><th>worst value</th>
<th>worst margin</th><th>what drives it: fitted formula (EC unit per mm or degree; [state]:
1 in that load state) and the failure rate per tercile of the strongest axis</th></tr>
{_ec_rows(result)}</table>
<h2>Margins</h2><figure><img src="{hist}" alt="margin histograms"><figcaption>Margin of
each sample per EC (distance to the nearer end of its range; below 0 fails).</figcaption></figure>
<h2>Yield against the tolerance scale</h2><figure><img src="{curve}" alt="yield curve">
<figcaption>Mount tolerances times the factor (load states unchanged).</figcaption></figure>
<h2>Worst sample and nominal</h2><div class="gallery">
<figure>{_picture(result.nominal, "nominal")}
<figcaption>Nominal (as designed)</figcaption></figure>
<figure>{_picture(result.worst, "worst sample")}
<figcaption>Worst: {escape(_sample_text(result))}</figcaption></figure></div>
<pre>{escape(result.summary())}</pre>
""")


def _setting_record(result: RobustnessResult | MarketsRobustness, inputs: RobustnessInputs,
                    out: Path, stage: Path) -> FileRecord:
    """The params file of the setting: the one given, else :data:`SETTING_FILE` (the
    setting's values and output size) written into ``stage``, the staging folder of
    ``out`` (where the record says it is)."""

    if inputs.params_file is not None:
        return file_record("params", inputs.params_file)
    write_text(stage / SETTING_FILE,
               f"# the setting rvmsim robustness judged ({result.scene_name})\n"
               + yaml.safe_dump(params_to_dict(result.params, result.output), sort_keys=False))
    return dataclasses.replace(file_record("params", stage / SETTING_FILE),
                               path=str((out / SETTING_FILE).resolve()))


def write_robustness_outputs(result: RobustnessResult, out_dir: str | Path,
                             inputs: RobustnessInputs | None = None) -> list[Path]:
    """Write ``robustness.json`` and ``robustness.html`` into ``out_dir``.

    ``inputs``: the files the run read (default: none given, so the setting is written as
    :data:`SETTING_FILE` beside them).  robustness.json records them under ``inputs``
    (each file's path and SHA-256) with the ``render_scale``.

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    how = inputs or RobustnessInputs()
    return write_json_and_page(
        result, out_dir, how, lambda setting: _input_records(result, how, setting),
        lambda setting, records: robustness_page(result, setting, records),
        {"criteria_file": None if how.criteria_file is None else str(how.criteria_file),
         "compensation": how.compensation, "markets": how.markets})


def write_json_and_page(result: RobustnessResult | MarketsRobustness, out_dir: str | Path,
                        how: RobustnessInputs,
                        records_for: Callable[[SettingRecord], list[FileRecord]],
                        page_for: Callable[[SettingRecord, list[FileRecord]], str],
                        inputs_doc: dict[str, Any]) -> list[Path]:
    """``robustness.json`` (``result.as_dict()`` with ``inputs``: the files read, their
    SHA-256, the render scale, the params and variation files and ``inputs_doc``) and
    ``robustness.html`` (``page_for``) in ``out_dir``; the setting written beside them when
    no params file was given.

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    out = Path(out_dir)
    js, html_path = out / "robustness.json", out / "robustness.html"
    # all into a staging folder, moved in when all is written (a full disk leaves the
    # earlier results as they were)
    with staged_folder(out) as stage:
        setting = SettingRecord(result.params, result.output,
                                _setting_record(result, how, out, stage))
        records = records_for(setting)
        doc = {**result.as_dict(), "inputs": {
            "files": [r.as_dict() for r in records], "render_scale": how.render_scale,
            "params_file": setting.file.path,
            "variation_file": None if how.variation_file is None else str(how.variation_file),
            **inputs_doc}}
        write_text(stage / js.name, json.dumps(doc, indent=2, default=json_default) + "\n")
        write_text(stage / html_path.name, page_for(setting, records))
    return [js, html_path]
