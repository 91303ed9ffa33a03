"""The sign-off's content and its summary: what the sheet judges (:func:`verdict_checks`),
whether it passes, and the summary section that says so with its figures
(:mod:`rvmsim.report.signoff_page` lays out the rest of the page)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from .guidelines import GUIDELINE_TABLE, GuidelineFigures, guidelines_summary_html
from .market_rows import all_markets_pass, markets_verdict_text
from .page import escape
from .provenance import FileRecord, Provenance
from .records import EolRecord, RobustnessRecord, ValidationRecord
from .setting import SettingRecord

if TYPE_CHECKING:
    from ..criteria import EcResult
    from ..isp import OutputSpec

__all__ = ["SignoffContent", "Check", "verdict_checks", "sheet_passes", "summary_html",
           "COMPENSATION_ROLE", "failure_groups",
           "compensation_text", "pct_text", "NO_ROBUSTNESS"]

#: The files table's role of the compensation model the yield assumes.
COMPENSATION_ROLE = "compensation (robustness)"

#: The red line of a sign-off without a robustness result.
NO_ROBUSTNESS = ("Robustness not run: the yield over mount tolerances and load states is not "
                 "known, so this setting is judged at the nominal pose only.")

@dataclass(frozen=True)
class SignoffContent:
    """Everything the page shows."""

    title: str
    run_dir: str
    setting: SettingRecord
    files: list[FileRecord]
    provenance: Provenance
    record_output: OutputSpec
    tuning_output: OutputSpec
    ec: EcResult
    display: np.ndarray
    annotated: np.ndarray
    ec_pictures: dict[str, np.ndarray]
    robustness: RobustnessRecord | None = None
    robustness_same_setting: bool = True
    changed_files: list[str] = field(default_factory=list)
    validation: ValidationRecord | None = None
    eol: EolRecord | None = None
    reviewer: str = ""
    #: The command reproducing each distinct failure, by its first sample's index.
    repro: dict[str, str] = field(default_factory=dict)
    #: A markets run's ``best/markets.json`` (None: not a markets run), and whether it is of
    #: the trial signed off here.
    markets: dict[str, Any] | None = None
    markets_same_trial: bool = True
    #: Why a given record is not of this setting or vehicle (signed with
    #: ``--allow-other-setting``): a red banner at the top.
    other_setting: tuple[str, ...] = ()
    #: The least yield that passes (None: none given) and where it came from.
    min_yield: float | None = None
    min_yield_source: str = ""
    #: The car's parking guidelines through the setting (the ECU table signed with it).
    guidelines: GuidelineFigures = field(
        default_factory=lambda: GuidelineFigures(reason="not computed"))

    @cached_property
    def checks(self) -> tuple[Check, ...]:
        """What the sheet judges (:func:`verdict_checks`), worked out once."""
        return tuple(verdict_checks(self))


def failure_groups(failing: Sequence[dict[str, Any]]) -> list[tuple[str, list[dict[str, Any]]]]:
    """Failing samples (robustness.json's) grouped by what fails on them (their set of
    failing ECs, as text), in order of first appearance: the sheet gives one reproduce
    command per group, for its first sample."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for s in failing:
        groups.setdefault(", ".join(sorted(map(str, s.get("failed", [])))), []).append(s)
    return list(groups.items())


def pct_text(est: dict[str, Any]) -> str:
    lo, hi = (float(v) for v in est["ci95"])
    return (f'{100 * float(est["yield"]):.1f} % (95 % CI {100 * lo:.1f}–{100 * hi:.1f} %, '
            f'{est.get("n_pass", "?")} of {est.get("n", "?")} samples)')


@dataclass(frozen=True)
class Check:
    """One line of the sheet's verdict: what was judged, whether it passes (None: not
    judged, e.g. no robustness folder given) and the figure that says so."""

    name: str
    passed: bool | None
    detail: str


def verdict_checks(c: SignoffContent) -> list[Check]:
    """What the sheet judges, in the summary's order: the ECs at the display output of
    record, the markets (a markets run), the yield against the least yield, the
    validation and the end-of-line station (each when given).  The sheet passes when no
    check fails (:func:`sheet_passes`)."""
    checks = [Check("ECs at the display output of record", c.ec.passed,
                    "every EC passes" if c.ec.passed else "failing: " + ", ".join(
                        e.id for e in c.ec.items if e.enabled and not e.passed))]
    if c.markets is not None:
        ok = all_markets_pass(c.markets) and c.markets_same_trial
        checks.append(Check("Markets", ok, markets_verdict_text(c.markets)
                            if c.markets_same_trial else "not judged for this setting"))
    r = c.robustness
    if r is None:
        checks.append(Check("Production yield", None, "robustness not run"))
    elif c.min_yield is None:
        checks.append(Check("Production yield", None, f"{100 * float(r.doc['yield']):.1f} %, "
                            "no least yield given"))
    else:
        ok = float(r.doc["yield"]) >= c.min_yield and c.robustness_same_setting
        checks.append(Check("Production yield", ok, f"{100 * float(r.doc['yield']):.1f} % "
                            f"{'≥' if float(r.doc['yield']) >= c.min_yield else '<'} "
                            f"{100 * c.min_yield:g} %" + ("" if c.robustness_same_setting
                                                          else " (of another setting)")))
    v = c.validation
    if v is not None:
        ok = (bool(v.single["passed"]) if v.single is not None
              else all(row["verdict"] == "PASS" for row in v.rows))
        checks.append(Check("Validation against a real capture", ok,
                            "passes" if ok else "fails"))
    e = c.eol
    if e is not None:
        checks.append(Check("End-of-line station", e.doc["passed"] == e.doc["cars"],
                            f"{e.doc['passed']} of {e.doc['cars']} cars pass"))
    return checks


def sheet_passes(checks: Sequence[Check]) -> bool:
    """Whether no check of the sheet fails (one not judged does not fail it)."""
    return all(ch.passed is not False for ch in checks)


def _badge(passed: bool | None, text: str) -> str:
    if passed is None:
        return f'<span class="amber">{escape(text)}</span>'
    return f'<span class="badge {"pass" if passed else "fail"}">{escape(text)}</span>'


def _limiting(doc: dict[str, Any] | None) -> str:
    """The limiting EC of a yield (robustness.json's ``limiting``) in words."""
    lim = None if doc is None else doc.get("limiting")
    if not isinstance(lim, dict):
        return "none (no EC fails on any sample)" if doc is not None and "limiting" in doc \
            else "not recorded (a robustness.json of an earlier rvmsim)"
    return (f"{lim.get('id')} {lim.get('name', '')}, fails on "
            f"{100 * float(lim.get('failure_rate', 0)):.1f} % of the samples")


def _yield_rows(c: SignoffContent, checks: Sequence[Check]) -> list[tuple[str, str]]:
    """The summary's yield rows: after and before compensation with their intervals, the
    limiting EC, the least yield and the compensation model."""
    r = c.robustness
    if r is None:
        return [("Production yield", f'<span class="red">{escape(NO_ROBUSTNESS)}</span>')]
    doc = r.doc
    cls = "red" if not c.robustness_same_setting else ""
    before = doc.get("yield_before_compensation")
    rows = [("Production yield" + (" after end-of-line compensation" if before else ""),
             f'<span class="{cls}"><b>{escape(pct_text(doc))}</b></span>')]
    if before:
        rows.append(("… before compensation", escape(pct_text(before))))
    rows.append(("Limiting EC (fails on most samples)", escape(_limiting(doc))
                 + ("" if not before else "; before compensation: "
                    + escape(_limiting(before)))))
    check = next(ch for ch in checks if ch.name == "Production yield")
    least = ("no least yield given (<code>--min-yield</code>, or <code>min_yield</code> in "
             "the variation file)" if c.min_yield is None else
             f"{100 * c.min_yield:g} % ({escape(c.min_yield_source)}): "
             + _badge(check.passed, "PASS" if check.passed else "FAIL"))
    rows.append(("Least yield that passes", least))
    comp = doc.get("compensation")
    if isinstance(comp, dict):
        rows.append(("Compensation model (what the yield after it assumes)",
                     escape(compensation_text(comp))))
    return rows


def compensation_text(comp: dict[str, Any]) -> str:
    """A compensation model (robustness.json's ``compensation``) in one line: its law,
    the values written per car with their ranges, the station's σ, the load it measures
    at, and where the model came from."""
    ranges = comp.get("ranges") or {}
    written = ", ".join(
        f"{name}" + (f" {float(ranges[name][0]):g}…{float(ranges[name][1]):g}°"
                     if name in ranges else "") for name in comp.get("params") or [])
    st = comp.get("station") or {}
    at = st.get("measured_at") or "the variation's first load state"
    return (f"law {comp.get('law')}; writes {written}; station σ "
            f"{st.get('angle_sigma_deg')}° / {st.get('position_sigma_mm')} mm "
            f"(body edge {st.get('edge_sigma_px')} px); measured at {at}; "
            f"model: {comp.get('source')}")


def summary_html(c: SignoffContent) -> str:
    """The summary section: the verdict and every figure the sheet judges."""
    checks = c.checks
    ok = sheet_passes(checks)
    failing = [ch.name for ch in checks if ch.passed is False]
    unjudged = [ch.name for ch in checks if ch.passed is None]
    verdict = (_badge(ok, "PASS" if ok else "FAIL") + " "
               + escape("; ".join(f"{ch.name}: {ch.detail}" for ch in checks
                                  if ch.passed is False) if failing else
                        "every check below passes")
               + ("" if not unjudged else
                  f' <span class="amber">not judged: {escape(", ".join(unjudged))}</span>'))
    nominal = checks[0]
    rows = [("Verdict", verdict),
            (nominal.name + " (nominal pose)",
             _badge(nominal.passed, nominal.detail)
             + f" {c.record_output.width} × {c.record_output.height} px")]
    if c.markets is not None:
        mk = checks[1]
        rows.append(("Markets (one setting judged at each market's site)",
                     _badge(mk.passed, mk.detail if c.markets_same_trial else
                            f"not known for this setting (best/markets.json is of trial "
                            f"{c.markets.get('trial')})")))
    rows += _yield_rows(c, checks)
    v = c.validation
    rows.append(("Validation against a real capture", "not given" if v is None else escape(
        ("PASS" if v.single["passed"] else "FAIL") if v.single is not None else
        f"{sum(r['verdict'] == 'PASS' for r in v.rows)} of {len(v.rows)} captures pass")))
    e = c.eol
    rows.append(("End-of-line station", "not given" if e is None else escape(
        f"{e.doc['passed']} of {e.doc['cars']} cars pass")))
    rows.append(("Parking guidelines (the ECU table signed with the setting)",
                 guidelines_summary_html(c.guidelines, GUIDELINE_TABLE)))
    body = "".join(f"<tr><th>{escape(a)}</th><td>{b}</td></tr>" for a, b in rows)
    return (f'<section id="verdict"><h2>Summary</h2><table>{body}</table>'
            '<p class="muted">The figures are what the tool measured; the decision is '
            "the reviewer's (the signature block below).</p></section>")
