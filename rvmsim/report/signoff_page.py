"""The sections of the sign-off page (:mod:`rvmsim.report.signoff` gathers what they show).

Every string from a user's files (scene, file and capture names, the reviewer) is
HTML-escaped; pictures are PNG ``data:`` URIs; the page has no scripts and no external
assets, and prints on A4 (``@media print`` rules keep rows and figures whole).
"""

from __future__ import annotations

from typing import Any

from .guidelines import GUIDELINE_TABLE, guidelines_html
from .market_rows import markets_html
from .page import escape, img_tag, page, path_html, sha_html
from .provenance import files_table, provenance_html
from .setting import by_load_html, setting_html, variation_html, worst_margin_text
from .signoff_summary import (COMPENSATION_ROLE, NO_ROBUSTNESS, SignoffContent,
                              failure_groups, pct_text, summary_html)
from ..criteria.annotate import spelled_name
from ..criteria.canvas import unit_text

__all__ = ["signoff_html", "SECTION_IDS", "NO_ROBUSTNESS", "SignoffContent"]

#: The page's sections, in order (each an element id).
#: The signature block follows the summary (what the witness signs); the commands that
#: reproduce the failing samples close the sheet as an appendix.
SECTION_IDS: tuple[str, ...] = ("verdict", "signature", "setting", "inputs", "tool", "ecs",
                                "guidelines", "yield", "failing-samples", "validation", "eol",
                                "reproduce")

_CSS = """<style>
.red{color:#c02828;font-weight:bold}.amber{color:#8a5a00;font-weight:bold}.redbox{border:2px solid #c02828;padding:.5em .8em}
table.sign td{height:2.6em;min-width:16em}
.closeups{display:grid;grid-template-columns:1fr 1fr;gap:4mm}
.closeups figure{margin:0;display:block}.closeups img{width:100%;display:block}
.closeups figcaption{max-width:none}
@media print{body{max-width:none;margin:0;font-size:10pt}h2,h3{page-break-after:avoid}
tr,figure,img,table.sign{page-break-inside:avoid}nav{display:none}}
@page{size:A4;margin:14mm}
</style>"""


def _setting(c: SignoffContent) -> str:
    return ('<section id="setting"><h2>The setting</h2>'
            f'<p>Rank 1 of the run {path_html(c.run_dir)}, for tuning output '
            f"{c.tuning_output.width} × {c.tuning_output.height} px.</p>"
            f"{setting_html(c.setting)}</section>")


def _inputs(c: SignoffContent) -> str:
    warn = "" if not c.changed_files else (
        '<p class="redbox">Changed since the robustness run (its recorded SHA-256 differs): '
        + ", ".join(f"{path_html(p)}" for p in c.changed_files) + "</p>")
    return (f'<section id="inputs"><h2>Input files</h2>{warn}{files_table(c.files)}'
            "</section>")


def _tool(c: SignoffContent) -> str:
    return f'<section id="tool"><h2>Tool</h2>{provenance_html(c.provenance)}</section>'


def _worst_margin(e: dict[str, Any]) -> str:
    """A robustness.json EC's worst margin over the samples (✓/✗ for a yes/no EC)."""
    low, high = e.get("range") or (None, None)
    return worst_margin_text(low, high, int(e.get("n_fail") or 0), e.get("worst_margin"),
                             e.get("unit", ""))


def _ec_rows(c: SignoffContent) -> str:
    rows = []
    for item in c.ec.items:
        st = "off" if not item.enabled else ("pass" if item.passed else "fail")
        rng = (f"[{'–' if item.low is None else f'{item.low:g}'}, "
               f"{'–' if item.high is None else f'{item.high:g}'}]")
        value = "—" if item.value is None else f"{item.value:.4g}"
        rows.append(
            f'<tr class="{st}"><td class="ecid">{escape(item.id)}</td><td>{escape(item.name)}</td>'
            f'<td class="num">{escape(value)} {escape(item.unit)}</td>'
            f'<td class="num">{escape(rng)} {escape(item.unit)}</td>'
            f'<td class="num">{escape(item.margin_text(unit_text(item.unit)))}</td>'
            f"<td>{escape(st)}</td></tr>")
    return "".join(rows)


def _closeups(c: SignoffContent) -> str:
    """Each enabled EC's close-up, two to a row (what it measures, labels readable on paper)."""
    figs = []
    for item in c.ec.items:
        pic = c.ec_pictures.get(item.id)
        if pic is None:
            continue
        st = "pass" if item.passed else "fail"
        figs.append(f'<figure class="closeup {st}">{img_tag(pic, f"EC {item.id}")}'
                    f'<figcaption><span class="ecid">{escape(item.id)}</span> '
                    f"{escape(spelled_name(item.name))}: {escape(st)}</figcaption></figure>")
    return f'<div class="closeups">{"".join(figs)}</div>' if figs else ""


def _ecs(c: SignoffContent) -> str:
    o = c.record_output
    return (f'<section id="ecs"><h2>Evaluation criteria at the display output of record '
            f"({o.width} × {o.height} px)</h2>"
            f"<p>EC score <b>{c.ec.score:.4g}</b>; criteria {escape(c.ec.criteria_name)}; "
            "full evaluation path (the whole fisheye label image through the ISP). Margin: "
            "signed distance of the value inside its range, in the EC's unit (below 0 "
            "fails).</p><table><tr><th>EC</th><th>measurement</th><th>value</th>"
            "<th>limit</th><th>margin</th><th>result</th></tr>"
            f"{_ec_rows(c)}</table><h3>Each EC, close up</h3>{_closeups(c)}"
            f"<figure>{img_tag(c.display, 'display picture')}<figcaption>The RVM picture at "
            f"{o.width} × {o.height} px.</figcaption></figure>"
            f"<figure>{img_tag(c.annotated, 'annotated EC image')}<figcaption>Every EC drawn "
            "on it, with the results panel.</figcaption></figure></section>")


def _yield_ec_rows(doc: dict[str, Any]) -> str:
    before = {e.get("id"): e for e in (doc.get("yield_before_compensation") or {}).get("ecs")
              or []}
    rows = []
    for e in doc["ecs"]:
        if not e.get("enabled", True):
            continue
        b = before.get(e["id"])
        cls = "fail" if e.get("n_fail") else "pass"
        rows.append(
            f'<tr class="{cls}"><td class="ecid">{escape(e["id"])}</td>'
            f'<td>{escape(e.get("name", ""))}</td>'
            + ("" if not before else
               f'<td class="num">{100 * float((b or {}).get("failure_rate", 0)):.1f} %</td>')
            + f'<td class="num">{100 * float(e.get("failure_rate", 0)):.1f} %</td>'
            f'<td class="num">{escape(_worst_margin(e))}'
            "</td></tr>")
    head = ("<tr><th>EC</th><th>measurement</th>" + ("<th>fails before compensation</th>"
                                                     if before else "")
            + "<th>fails</th><th>worst margin</th></tr>")
    return f"<table>{head}{''.join(rows)}</table>"


def _yield(c: SignoffContent) -> str:
    r = c.robustness
    if r is None:
        return (f'<section id="yield"><h2>Production yield</h2><p class="red">'
                f"{escape(NO_ROBUSTNESS)}</p><p>Make it with <code>rvmsim robustness SCENE "
                "--params PARAMS --out DIR</code> and pass <code>--robustness DIR</code>."
                "</p></section>")
    doc = r.doc
    warn = "" if c.robustness_same_setting else (
        '<p class="redbox">This robustness result judged a different setting than the one '
        "signed here: its yield is not this setting's.</p>")
    before = doc.get("yield_before_compensation")
    line = (f"<p>Yield <b>{escape(pct_text(doc))}</b>"
            + ("" if not before else f"; before end-of-line compensation "
               f"<b>{escape(pct_text(before))}</b>")
            + f". Seed {escape(doc['seed'])}; criteria {escape(doc.get('criteria', ''))}; "
            f"from {path_html(r.path.resolve())}.</p>")
    by_load = by_load_html(doc["yield_by_load"], before.get("by_load") if before else None)
    comp = doc.get("compensation")
    return (f'<section id="yield"><h2>Production yield</h2>{warn}{line}'
            f"<h3>Per load state</h3>{by_load}<h3>Per EC</h3>{_yield_ec_rows(doc)}"
            f"<h3>Tolerances and load states</h3>{variation_html(doc['variation'])}"
            + ("" if not isinstance(comp, dict) else
               f"<h3>End-of-line compensation model</h3>{_compensation_table(c, comp)}")
            + "</section>")


def _compensation_table(c: SignoffContent, comp: dict[str, Any]) -> str:
    """Every value of the compensation model the yield after compensation assumes, and
    its source: a file with its SHA-256, or the built-in default of this rvmsim."""
    src = str(comp.get("source", ""))
    rec = next((f for f in c.files if f.role == COMPENSATION_ROLE), None)
    where = (f"built-in default of rvmsim {escape(c.provenance.version)} (no file: every "
             "value is below)" if rec is None or rec.sha256 is None else
             f"{path_html(rec.path)} sha256 {sha_html(rec.sha256)}")
    st = comp.get("station") or {}
    ranges = comp.get("ranges") or {}
    rows = [("source", where if src else "—"),
            ("law", escape(comp.get("law"))),
            ("values written per car", escape(", ".join(map(str, comp.get("params") or [])))),
            *((f"range of {escape(n)}", f"{float(lo):g} … {float(hi):g}°")
              for n, (lo, hi) in ranges.items()),
            ("station σ: angle, position", f"{escape(st.get('angle_sigma_deg'))}°, "
                                           f"{escape(st.get('position_sigma_mm'))} mm"),
            ("station σ: body edge on the capture", f"{escape(st.get('edge_sigma_px'))} px"),
            ("load state at the station", escape(st.get("measured_at")
                                                 or "the variation's first")),
            ("a car inside the station's uncertainty", escape(st.get("marginal"))),
            ("reference points", escape(comp.get("reference"))),
            ("EC evaluations per car (ec-solve)", escape(comp.get("budget"))),
            ("search stops", escape(comp.get("stop")))]
    return "<table>" + "".join(f"<tr><th>{a}</th><td>{b}</td></tr>" for a, b in rows) + "</table>"


def _failure_groups(c: SignoffContent) -> list[tuple[str, list[dict[str, Any]]]]:
    """The sheet's failing samples by what fails on them (:func:`failure_groups`)."""
    return failure_groups(c.robustness.failing if c.robustness is not None else [])


def _failing(c: SignoffContent) -> str:
    r = c.robustness
    if r is None:
        return ('<section id="failing-samples"><h2>Failing samples</h2><p class="red">'
                "Robustness not run: no samples.</p></section>")
    failing = r.failing
    if not failing:
        return ('<section id="failing-samples"><h2>Failing samples</h2><p>None of the '
                f"{len(r.doc['samples'])} samples fails.</p></section>")
    ref = {str(s["index"]): f"R{k}" for k, (_, group) in enumerate(_failure_groups(c), 1)
           for s in group}
    rows = []
    for s in failing:
        offsets = ", ".join(f"{k.split('_')[0]} {float(s.get(k, 0.0)):+.3g}" for k in (
            "x_mm", "y_mm", "z_mm", "yaw_deg", "pitch_deg", "roll_deg"))
        rows.append(f"<tr><td class=\"num\">{escape(s['index'])}</td>"
                    f"<td>{escape(s.get('load', ''))}</td><td>{escape(offsets)}</td>"
                    f"<td class=\"ecid\">{escape(', '.join(map(str, s.get('failed', []))))}</td>"
                    f"<td>{escape(ref.get(str(s['index']), ''))}</td></tr>")
    return ('<section id="failing-samples"><h2>Failing samples</h2>'
            f"<p>{len(failing)} of {len(r.doc['samples'])} samples fail. The appendix gives, "
            "for each distinct failure (the same ECs failing), a command that writes one such "
            'car as a scene and renders it in full (docs/robustness.md, "Any sample as a '
            'scene").'
            + ("" if not r.doc.get("compensation") else
               " The exported car is the car before compensation: <code>rvmsim evaluate"
               "</code> judges it with the platform setting; its per-car values are the "
               "sample's <code>correction</code> in robustness.json.")
            + '</p><table><tr><th>sample</th><th>load</th>'
            "<th>offsets (mm, °)</th><th>failing</th><th>reproduce</th></tr>"
            f"{''.join(rows)}</table></section>")


def _reproduce(c: SignoffContent) -> str:
    """The appendix: one command per distinct failure, for its first sample."""
    groups = _failure_groups(c)
    if not groups:
        return ('<section id="reproduce"><h2>Appendix: reproducing a failure</h2><p>No '
                "sample fails.</p></section>")
    rows = "".join(
        f"<tr><td>R{k}</td><td class=\"ecid\">{escape(ecs)}</td><td>{len(group)}: "
        f"{escape(', '.join(str(s['index']) for s in group))}</td>"
        f"<td><code>{escape(c.repro.get(str(group[0]['index']), ''))}</code></td></tr>"
        for k, (ecs, group) in enumerate(groups, 1))
    return ('<section id="reproduce"><h2>Appendix: reproducing a failure</h2>'
            "<p>One command per distinct failure, for its first sample (the others differ "
            "only in their offsets).</p><table><tr><th></th><th>failing</th><th>samples</th>"
            f"<th>command</th></tr>{rows}</table></section>")


def _validation(c: SignoffContent) -> str:
    v = c.validation
    if v is None:
        return ('<section id="validation"><h2>Validation against a real capture</h2>'
                "<p>Not given (<code>--validation DIR</code>, the folder "
                "<code>rvmsim validate</code> writes).</p></section>")
    if v.single is not None:
        d = v.single
        rows = "".join(
            f'<tr class="{"pass" if k.get("passed") else "fail"}"><td>{escape(k.get("name"))}'
            f'</td><td class="num">{escape(k.get("value"))}</td><td class="num">≤ '
            f'{escape(k.get("limit"))}</td><td>{"pass" if k.get("passed") else "FAIL"}</td></tr>'
            for k in d["checks"] if isinstance(k, dict))
        body = (f"<p>Capture {path_html(d['capture'])} of "
                f"{escape(d.get('scene', ''))}: <b>{'PASS' if d['passed'] else 'FAIL'}</b>."
                f"</p><table><tr><th>check</th><th>value</th><th>limit</th><th></th></tr>"
                f"{rows}</table>")
    else:
        rows = "".join(f"<tr class=\"{'pass' if r['verdict'] == 'PASS' else 'fail'}\">"
                       f"<td>{path_html(r.get('capture'))}</td>"
                       f"<td>{escape(r['verdict'])}</td><td>{escape(r.get('error') or '')}</td>"
                       "</tr>" for r in v.rows)
        body = f"<table><tr><th>capture</th><th>verdict</th><th>error</th></tr>{rows}</table>"
    return ('<section id="validation"><h2>Validation against a real capture</h2>'
            f"<p>From {path_html(v.path.resolve())}.</p>{body}</section>")


def _eol(c: SignoffContent) -> str:
    e = c.eol
    if e is None:
        return ('<section id="eol"><h2>End-of-line station</h2><p>Not given '
                "(<code>--eol DIR</code>, the folder <code>rvmsim eol</code> writes).</p>"
                "</section>")
    d = e.doc
    rows = "".join(
        f"<tr class=\"{'pass' if r['verdict'] == 'PASS' else 'fail'}\">"
        f"<td>{escape(r.get('name', r.get('capture', '')))}</td><td>{escape(r['verdict'])}</td>"
        f"<td>{escape('; '.join(map(str, r.get('reasons') or [])))}</td></tr>"
        for r in d["results"] if isinstance(r, dict))
    return ('<section id="eol"><h2>End-of-line station</h2>'
            f"<p>{escape(d['passed'])} of {escape(d['cars'])} cars pass; platform setting "
            f"{path_html(d['params_file'])}; from "
            f"{path_html(e.path.resolve())}.</p>"
            f"<table><tr><th>car</th><th>verdict</th><th>reasons</th></tr>{rows}</table>"
            "</section>")


def _signature(c: SignoffContent) -> str:
    name = escape(c.reviewer) if c.reviewer else ""
    return ('<section id="signature"><h2>Signature</h2><table class="sign">'
            f"<tr><th>Reviewer</th><td>{name}</td></tr><tr><th>Date</th><td></td></tr>"
            "<tr><th>Decision (approved / rejected)</th><td></td></tr>"
            "<tr><th>Signature</th><td></td></tr></table></section>")


def signoff_html(c: SignoffContent) -> str:
    """The whole sign-off document."""
    nav = " · ".join(f'<a href="#{s}">{escape(s.replace("-", " "))}</a>' for s in SECTION_IDS)
    head = (f"{_CSS}<h1>Sign-off: {escape(c.title)}</h1><p class=\"muted\">ISP setting "
            f"sign-off sheet, made {escape(c.provenance.date)} by rvmsim "
            f"{escape(c.provenance.version)} from the run {path_html(c.run_dir)}."
            f"</p><nav><p>{nav}</p></nav>")
    if c.markets is not None:
        nav = nav.replace("</a>", '</a> · <a href="#markets">markets</a>', 1)
    markets = "" if c.markets is None else markets_html(c.markets, c.run_dir)
    banner = "" if not c.other_setting else (
        '<p class="redbox"><b>Signed with records of another setting or vehicle</b> '
        "(--allow-other-setting): " + "; ".join(escape(w) for w in c.other_setting)
        + ". Their figures below do not describe this setting.</p>")
    body = (head + banner + summary_html(c) + _signature(c) + markets + _setting(c) + _inputs(c)
            + _tool(c) + _ecs(c) + guidelines_html(c.guidelines, GUIDELINE_TABLE)
            + _yield(c) + _failing(c) + _validation(c) + _eol(c)
            + _reproduce(c))
    return page(f"Sign-off: {c.title}", body)
