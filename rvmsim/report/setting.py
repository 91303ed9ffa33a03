"""Pieces the robustness page and the sign-off page share: the ISP setting judged (its 14
values, its file and the file's SHA-256), the variation model (tolerances and load states),
the yield per load state, and the EC margin.

The variation is read in its JSON form (:meth:`rvmsim.robust.Variation.as_dict`: what
``robustness.json`` records), so a page made from a result in memory and one made from a
stored ``robustness.json`` show the same table.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .page import escape, path_html, sha_html
from .provenance import FileRecord
from ..criteria import is_yes_no
from ..isp import PARAM_SPECS

if TYPE_CHECKING:
    from ..isp import IspParams, OutputSpec

__all__ = ["SettingRecord", "setting_html", "params_table", "variation_html", "by_load_html",
           "fmt_margin", "worst_margin_text", "AXIS_TEXT"]

#: The mount axes as a page names them, with their unit.
AXIS_TEXT: dict[str, tuple[str, str]] = {
    "x_mm": ("position x (driver's side)", "mm"), "y_mm": ("position y (down)", "mm"),
    "z_mm": ("position z (rearward)", "mm"), "yaw_deg": ("yaw", "°"),
    "pitch_deg": ("pitch", "°"), "roll_deg": ("roll", "°"),
}


@dataclass(frozen=True)
class SettingRecord:
    """An ISP setting as judged: its values, the RVM output they were made for, and the
    params file holding them (``file.sha256`` is that file's hash)."""

    params: IspParams
    output: OutputSpec
    file: FileRecord


def params_table(params: IspParams) -> str:
    """The 14 ISP parameters: name, the paper's name, value (full precision), unit."""

    rows = "".join(
        f"<tr><td>{escape(s.name)}</td><td>{escape(s.paper_name)}</td>"
        f'<td class="num">{getattr(params, s.name)!r}</td><td>{escape(s.unit)}</td></tr>'
        for s in PARAM_SPECS)
    return ('<table class="params"><tr><th>parameter</th><th>paper name</th><th>value</th>'
            f"<th>unit</th></tr>{rows}</table>")


def setting_html(setting: SettingRecord) -> str:
    """The params file with its SHA-256, the output size, then :func:`params_table`."""
    f, out = setting.file, setting.output
    digest = f.sha256 or f"— ({f.note})"
    return (f'<table class="setting"><tr><th>params file</th><td>{path_html(f.path)}'
            f'</td></tr><tr><th>SHA-256</th><td>{sha_html(digest)}</td>'
            f"</tr><tr><th>output of the file</th><td>{out.width} × {out.height} px, "
            f"{'mirrored' if out.mirror else 'not mirrored'}</td></tr></table>"
            + params_table(setting.params))


def _axis_text(spec: Mapping[str, Any]) -> tuple[str, str]:
    """(distribution, largest offset) of one axis's JSON form."""
    kind = str(spec.get("kind", "fixed"))
    if kind == "uniform":
        h = float(spec.get("half_width", 0.0))
        return f"uniform ±{h:g}", f"{h:g}"
    if kind == "normal":
        s, t = float(spec.get("sigma", 0.0)), float(spec.get("truncate", 3.0))
        return f"normal σ {s:g}, cut at ±{t:g} σ", f"{s * t:g}"
    return "fixed", "0"


def variation_html(variation: Mapping[str, Any]) -> str:
    """The tolerance figures (per mount axis: distribution, σ or half width, largest
    offset, unit), the rendered position levels and the load states (height, pitch,
    probability), from the variation's JSON form."""
    mount = variation.get("mount") or {}
    rows = []
    for axis, (name, unit) in AXIS_TEXT.items():
        dist, bound = _axis_text(mount.get(axis) or {})
        rows.append(f"<tr><td>{escape(name)}</td><td>{escape(dist)}</td>"
                    f'<td class="num">±{escape(bound)}</td><td>{escape(unit)}</td></tr>')
    loads = variation.get("load_states") or []
    load_rows = "".join(
        f"<tr><td>{escape(s.get('name'))}</td><td class=\"num\">{float(s.get('height_mm', 0)):+g}"
        f"</td><td class=\"num\">{float(s.get('pitch_deg', 0)):+g}</td>"
        f"<td class=\"num\">{100 * float(s.get('probability', 1)):.1f} %</td></tr>"
        for s in loads if isinstance(s, Mapping))
    return (f'<p>Variation model: <code>{escape(variation.get("source", "—"))}</code>; '
            f'positions rendered at {escape(variation.get("position_levels", "—"))} levels per '
            "varying axis.</p>"
            '<table class="tolerances"><tr><th>mount axis</th><th>distribution</th>'
            f"<th>largest offset</th><th>unit</th></tr>{''.join(rows)}</table>"
            '<table class="load-states"><tr><th>load state</th><th>camera height (mm)</th>'
            "<th>body pitch (°, rear down)</th><th>share of cars</th></tr>"
            f"{load_rows}</table>")


def _pct_cell(est: Mapping[str, Any] | None) -> str:
    if not est:
        return "<td>—</td>"
    lo, hi = (float(v) for v in est.get("ci95", (math.nan, math.nan)))
    return (f'<td class="num">{100 * float(est["yield"]):.1f} % <small>({100 * lo:.1f}–'
            f'{100 * hi:.1f} %, {est.get("n_pass", "?")} of {est.get("n", "?")})</small></td>')


def by_load_html(after: Mapping[str, Any], before: Mapping[str, Any] | None = None) -> str:
    """The yield per load state (JSON forms of ``yield_by_load``), with the yield before
    compensation beside it when given."""
    head = "<tr><th>load state</th>" + ("<th>before compensation</th><th>after compensation"
                                        "</th>" if before else "<th>yield (95 % CI)</th>") + "</tr>"
    rows = "".join(
        f"<tr><td>{escape(name)}</td>" + (_pct_cell(before.get(name)) if before else "")
        + _pct_cell(est) + "</tr>" for name, est in after.items())
    return f'<table class="by-load">{head}{rows}</table>'


def worst_margin_text(low: float | None, high: float | None, n_fail: int,
                      worst_margin: float | None, unit: str = "") -> str:
    """The worst margin over samples, as every table shows a margin
    (:meth:`rvmsim.criteria.EcValue.margin_text`): ✓/✗ for a yes/no EC (a range of one
    value: ✗ when any sample fails it), else the signed margin with its unit."""
    if is_yes_no(low, high):
        return "✗" if n_fail else "✓"
    return fmt_margin(worst_margin, unit)


def fmt_margin(margin: float | None, unit: str = "") -> str:
    """A margin as a cell: signed, 4 significant digits, with the unit."""
    if margin is None or not math.isfinite(margin):
        return "—"
    return f"{margin:+.4g}" + (f" {unit}" if unit else "")
