"""The markets of a markets run (``rvmsim tune --markets``) in its report and sign-off sheet.

Read from the run's ``best/markets.json`` (:mod:`rvmsim.tune.markets`): one row per market
(its title, EC score under the best setting, pass or fail, the binding criterion with its
value, the failing ECs), each market's annotated RVM image
(``best/markets/<member>/ec_annotated.png``) and, when no setting passes every market, why
(the ECs no setting can pass, the conflicting ECs of markets that pass alone but never
together).  Every string from the run's files is HTML-escaped.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from .page import data_uri, escape
from ..tune.markets import market_problem_lines

__all__ = ["markets_html", "markets_rows", "all_markets_pass",
           "markets_verdict_text"]


def all_markets_pass(doc: dict[str, Any]) -> bool:
    """Whether the best setting passes every market."""
    return all(bool(r["passed"]) for r in doc["markets"])


def markets_verdict_text(doc: dict[str, Any]) -> str:
    """``all markets pass`` only when every market passes, else the markets that fail."""
    if all_markets_pass(doc):
        return f"all markets pass ({len(doc['markets'])})"
    lost = [str(r["member"]) for r in doc["markets"] if not r["passed"]]
    return f"not every market passes: {', '.join(lost)} fail"


def _binding_text(b: dict[str, Any] | None) -> str:
    if not b:
        return "—"
    value = "—" if b.get("value") is None else f"{b['value']:.4g} {b.get('unit', '')}".strip()
    return f"{b.get('ec', '?')} {b.get('name', '')} = {value}"


def markets_rows(doc: dict[str, Any], run_dir: str | Path) -> list[dict[str, Any]]:
    """JSON-ready rows (signoff.json's ``markets``): member, market, title, EC score,
    passed, binding criterion, failing ECs and the annotated image's path."""
    best = Path(run_dir) / "best"
    return [{"member": r["member"], "market": r.get("market"), "title": r.get("title"),
             "ec_score": r.get("ec_score"), "passed": r["passed"],
             "binding": r.get("binding"), "failing": list(r.get("failing") or []),
             "annotated": str((best / str(r.get("images", "")) / "ec_annotated.png").resolve())}
            for r in doc["markets"]]


def _image(run_dir: Path, row: dict[str, Any]) -> str:
    """The market's annotated image as an ``<img>`` (data URI), or a note when missing."""
    path = run_dir / "best" / str(row.get("images", "")) / "ec_annotated.png"
    if not row.get("images") or not path.is_file():
        return f'<p class="muted">{escape(path)}: not found</p>'
    return (f'<img src="{data_uri(path.read_bytes())}" alt="{escape(row["member"])} '
            f'annotated ECs">')


def markets_html(doc: dict[str, Any], run_dir: str | Path, *,
                 section_id: str = "markets") -> str:
    """The markets section: the verdict, one row per market, the reasons when not every
    market passes, and each market's annotated image."""

    run_dir = Path(run_dir)
    ok = all_markets_pass(doc)
    rows = []
    for r in doc["markets"]:
        score = r.get("ec_score")
        rows.append(
            f'<tr class="{"pass" if r["passed"] else "fail"} market">'
            f'<td>{escape(r["member"])}</td><td>{escape(r.get("title") or "")}</td>'
            f'<td class="num">{"—" if score is None else f"{score:.4g}"}</td>'
            f'<td>{"pass" if r["passed"] else "FAIL"}</td>'
            f'<td>{escape(_binding_text(r.get("binding")))}</td>'
            f'<td>{escape(", ".join(r.get("failing") or [])) or "—"}</td></tr>')
    problems = market_problem_lines(doc) if not ok else []
    why = "" if not problems else (
        '<p class="fail"><b>No setting found passes every market:</b></p><ul class="why">'
        + "".join(f"<li>{escape(p)}</li>" for p in problems) + "</ul>")
    figures = "".join(
        f'<figure class="market-image">{_image(run_dir, r)}<figcaption>'
        f'{escape(r["member"])}: {escape(r.get("title") or "")}</figcaption></figure>'
        for r in doc["markets"])
    judged = doc.get("judged_at") or []
    at = f" at {judged[0]} × {judged[1]} px" if len(judged) == 2 else ""
    return (f'<section id="{escape(section_id)}"><h2>Markets</h2>'
            f'<p><span class="badge {"pass" if ok else "fail"}">'
            f'{escape(markets_verdict_text(doc))}</span> — the best setting (trial '
            f'{escape(doc.get("trial", "?"))}) judged at each market\'s site with its '
            f"criteria{at}; the binding criterion is the market's EC with the least score."
            f"</p><table><tr><th>market</th><th>title</th><th>EC score</th><th>result</th>"
            f"<th>binding criterion</th><th>failing ECs</th></tr>{''.join(rows)}</table>"
            f'{why}<div class="gallery">{figures}</div></section>')
