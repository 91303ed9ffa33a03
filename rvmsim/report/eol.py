"""The EOL station's page (``rvmsim eol``): one HTML page for a station run.

What the cars were judged by, a table with one row per car (verdict, measured deviation,
per-car values, the reason for a failure), every EC per car, and each car's corrected RVM
picture.  The pictures are the PNG files written beside the page (relative links), not
embedded: a station run may hold many cars.  Built with the page kit (:mod:`.page`); every
string from a user's files (scene name, capture names) is HTML-escaped.
"""

from __future__ import annotations

from pathlib import Path

from ..eol import CarResult, StationResult
from ..errors import RvmsimError
from ..storage import write_problem, write_text
from .page import escape, page, url_path

__all__ = ["eol_page", "write_eol_page"]

#: The page's file name.
PAGE_NAME = "eol.html"
_UNITS = {"h_pan": "°", "v_pan": "°", "tilt": "°", "h_shift": "px", "v_shift": "px"}


def eol_page(result: StationResult) -> str:
    """The whole HTML document for ``result``."""
    n, n_pass = len(result.cars), result.n_pass
    badge = "pass" if result.passed else "fail"
    comp = result.compensation
    station = comp.get("station", {})
    ranges = ", ".join(f"{k} [{lo:g}, {hi:g}]" for k, (lo, hi) in comp.get("ranges", {}).items())
    load = result.load_state
    body = f"""
<h1>EOL station: {escape(result.scene_name)}
<span class="badge {badge}">{n_pass} of {n} cars pass</span></h1>
<p>Scene {escape(result.scene_file)}; target <b>{escape(result.target)}</b>; cars measured at
load state <b>{escape(load.get("name", ""))}</b> (height {load.get("height_mm", 0):+g} mm,
pitch {load.get("pitch_deg", 0):+g}°). Platform setting {escape(result.params_file or "-")};
ECs ({escape(result.criteria)}) on the {result.output[0]}×{result.output[1]} RVM image.</p>
<p>Compensation ({escape(comp.get("source", ""))}, law {escape(str(comp.get("law", "")))}):
writes {escape(", ".join(result.written))}; allowed offsets {escape(ranges)}; station σ
{station.get("angle_sigma_deg", 0):g}° and {station.get("position_sigma_mm", 0):g} mm, the
body's edge {station.get("edge_sigma_px", 0):g} px (assumed: what calls a car marginal).
Cars: {", ".join(f"{n} {escape(st)}" for st, n in _statuses(result) if n)}.</p>
<h2>Cars</h2>{_car_table(result)}
<h2>ECs on each car's corrected picture</h2>{_ec_table(result)}
<h2>Corrected pictures</h2><div class="gallery">{"".join(_card(c) for c in result.cars)}</div>
<p class="muted">Time: {result.timings.get("total", 0):.1f} s ({result.timings.get("setup", 0):.1f} s
setting up the station, {result.timings.get("cars", 0) / max(n, 1):.2f} s per car).</p>
"""
    return page(f"EOL station: {result.scene_name}", body)


def _statuses(result: StationResult) -> list[tuple[str, int]]:
    """The cars by the station's verdict (pass, marginal, infeasible, fail, no pose)."""
    return [(st, result.count(st)) for st in ("pass", "marginal", "infeasible", "fail",
                                              "no pose")]


def _car_table(result: StationResult) -> str:
    head = ("<tr><th>car</th><th>verdict</th><th>Δx, Δy, Δz mm</th><th>Δyaw, Δpitch, Δroll °"
            "</th><th>corners (RMS px)</th>"
            + "".join(f"<th>{escape(p)}</th>" for p in result.written)
            + "<th>residual px</th><th>EC score</th><th>guideline table (SHA-256)</th>"
            "<th>reason</th></tr>")
    rows = []
    for c in result.cars:
        d, corr = c.deviation, c.correction
        pos = "-" if d is None else f"{d.x_mm:+.2f}, {d.y_mm:+.2f}, {d.z_mm:+.2f}"
        ang = "-" if d is None else f"{d.yaw_deg:+.3f}, {d.pitch_deg:+.3f}, {d.roll_deg:+.3f}"
        fit = "-" if c.rms_px is None else f"{c.landmarks} ({c.rms_px:.2f})"
        values = "".join(
            "<td class=\"num\">-</td>" if corr is None else
            f"<td class=\"num\">{corr.values[p]:.3f}{_UNITS.get(p, '')}</td>"
            for p in result.written)
        resid = "-" if corr is None else f"{corr.residual_rms_px:.2f}"
        score = "-" if c.ec is None else f"{c.ec.score:.3f}"
        table = c.files.get("guidelines")
        lines = ("-" if table is None or c.guidelines is None else
                 f'<a href="{escape(table)}"><code>{escape(table)}</code></a> '
                 f"<code>{c.guidelines.sha256[:16]}…</code>")
        rows.append(f'<tr class="{"pass" if c.passed else "fail"}"><td>{escape(c.name)}</td>'
                    f"<td>{c.verdict} ({escape(c.status)})</td><td class=\"num\">{pos}</td>"
                    f"<td class=\"num\">{ang}</td><td class=\"num\">{fit}</td>{values}"
                    f"<td class=\"num\">{resid}</td><td class=\"num\">{score}</td>"
                    f"<td>{lines}</td><td>{escape(c.reason)}</td></tr>")
    return f"<table>{head}{''.join(rows)}</table>"


def _ec_table(result: StationResult) -> str:
    first = next((c.ec for c in result.cars if c.ec is not None), None)
    if first is None:
        return "<p>No car's pose was recovered: no EC was measured.</p>"
    head = "<tr><th>car</th>" + "".join(
        f'<th title="{escape(i.name)}">{escape(i.id)}</th>' for i in first.items) + "</tr>"
    rows = []
    for c in result.cars:
        if c.ec is None:
            cells = f'<td colspan="{len(first.items)}">not measured</td>'
        else:
            cells = "".join(
                f'<td class="num {"off" if not i.enabled else "pass" if i.passed else "fail"}">'
                f'{"—" if i.value is None else f"{i.value:.3g}"}</td>' for i in c.ec.items)
        rows.append(f"<tr><td>{escape(c.name)}</td>{cells}</tr>")
    ranges = "".join(
        f"<td class=\"num\">[{'–' if i.low is None else f'{i.low:g}'}, "
        f"{'–' if i.high is None else f'{i.high:g}'}] {escape(i.unit)}</td>" for i in first.items)
    return f"<table>{head}{''.join(rows)}<tr><td>range</td>{ranges}</tr></table>"


def _card(car: CarResult) -> str:
    key = next((k for k in ("annotated", "rvm", "landmarks", "overlay") if k in car.files), None)
    picture = ("<p>(no picture)</p>" if key is None else
               f'<a href="{url_path(car.files[key])}"><img src="{url_path(car.files[key])}" '
               f'alt="{escape(car.name)}"></a>')
    what = ("corrected RVM picture, ECs drawn" if key in ("annotated", "rvm")
            else "landmarks (the pose was not recovered)")
    reason = f"<br>{escape(car.reason)}" if car.reason else ""
    return (f'<div class="card"><b>{escape(car.name)}</b> '
            f'<span class="badge {"pass" if car.passed else "fail"}">{car.verdict}</span>'
            f"{picture}<div class=\"muted\">{what}{reason}</div></div>")


def write_eol_page(result: StationResult, folder: str | Path) -> Path:
    """Write ``eol.html`` into ``folder`` (beside the cars' pictures); returns its path.

    Raises
    ------
    RvmsimError
        One line naming the file that cannot be written.
    """
    path = Path(folder) / PAGE_NAME
    try:
        write_text(path, eol_page(result))
    except OSError as err:
        raise RvmsimError(f"{path}: {write_problem(err)}") from None
    return path
