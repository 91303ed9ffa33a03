"""The parking guidelines of a setting on the pages people review (issue #46): the run
report's "Parking guidelines" section and the sign-off sheet's.

:func:`guideline_figures` draws the car's guidelines (:mod:`rvmsim.guidelines`) through an
ISP setting into the RVM image of record, and makes the ECU table of them over the car's
whole steering range (``RVMG``, :func:`rvmsim.guidelines.table.table_bytes`, the same bytes
``rvmsim guidelines`` writes as guidelines.bin for that setting).  The pages show the
pictures, the lines and the table's SHA-256, and write the table beside themselves, so the
hash names a file the reader has.  A scene without the car's running gear (or without a
vehicle) gets one line instead: "no guidelines: <reason>".

Convention
----------
Display px of the RVM image of record; steering-wheel angles in degrees, positive toward +X.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputFileError, RvmsimError
from ..guidelines import compute_guidelines, guideline_view, running_gear, steering_angles
from ..guidelines.coverage import covered_by, required_coverage
from ..guidelines.draw import draw_lines
from ..guidelines.files import shown_angle
from ..guidelines.project import DisplayLine
from ..guidelines.table import TABLE_VERSION, table_bytes
from ..isp import IspParams, OutputSpec
from ..pipeline import rvm_color
from ..render import FisheyeImages
from ..scene import Scene
from .page import escape, img_tag, sha_html, url_path

__all__ = ["GUIDELINE_TABLE", "GuidelineRow", "GuidelineFigures", "guideline_figures",
           "guideline_table_name", "guidelines_html", "guidelines_summary_html",
           "NO_GUIDELINES"]

#: The ECU table's file name beside a page named ``report.html`` or written into a folder.
GUIDELINE_TABLE = "guidelines.bin"

#: The words that open the line a page shows instead of the guidelines.
NO_GUIDELINES = "no guidelines"

#: Longest side of the pictures on a page, px (the straight-ahead one, the ±100 % one).
PICTURE_MAX_PX = 1280
EXTREMES_MAX_PX = 640


@dataclass(frozen=True)
class GuidelineRow:
    """One guideline as the pages list it.

    Attributes
    ----------
    name : str
        Its name (``mark_1m``, ``width_neg_x``, ``trajectory_pos_x``, …).
    kind : str
        ``"mark"``, ``"width"`` or ``"trajectory"``.
    steering_deg : float or None
        A trajectory line's steering-wheel angle, degrees; None for a static line.
    shown : bool
        Whether any of it lands on the RVM image.
    points : int
        Display points of its shown pieces.
    """

    name: str
    kind: str
    steering_deg: float | None
    shown: bool
    points: int


@dataclass(frozen=True, eq=False)
class GuidelineFigures:
    """What the pages show of a setting's guidelines (:func:`guideline_figures`).

    Attributes
    ----------
    reason : str or None
        Why there are none (the scene lacks the car's running gear, …); None when there are.
    output : OutputSpec or None
        The RVM image of record they are drawn on.
    steering_deg : tuple of float
        The steering-wheel angles the table covers, degrees, ascending.
    shown_deg : float
        The angle of the main picture (the one nearest straight ahead), degrees.
    picture : (H, W, 3) uint8 or None
        The RVM picture with the static lines and the trajectory lines of ``shown_deg``.
    extremes : (H, W, 3) uint8 or None
        The same with the trajectory lines at both ends of the steering range (±100 %);
        None with a single angle.
    rows : tuple of GuidelineRow
        The static lines, then the trajectory lines at ``shown_deg`` and at both ends.
    lines : int
        Lines in the table (static ones and every angle's trajectory lines).
    lines_shown : int
        Of those, the ones that land on the RVM image.
    table : bytes
        The ECU table (``RVMG``; empty without guidelines).
    covers : dict
        The test objects' required-visible areas the lines are drawn over, per site
        (:func:`rvmsim.guidelines.coverage.required_coverage`).
    """

    reason: str | None = None
    output: OutputSpec | None = None
    steering_deg: tuple[float, ...] = ()
    shown_deg: float = 0.0
    picture: np.ndarray | None = None
    extremes: np.ndarray | None = None
    rows: tuple[GuidelineRow, ...] = ()
    lines: int = 0
    lines_shown: int = 0
    table: bytes = b""
    covers: Mapping[str, Any] = field(default_factory=dict)

    @property
    def sha256(self) -> str | None:
        """The table's SHA-256 (hex), None without guidelines."""
        return None if self.reason is not None else hashlib.sha256(self.table).hexdigest()

    def angles_text(self) -> str:
        """The steering angles covered, in words (the table holds them to 0.1°)."""
        a = self.steering_deg
        if not a:
            return "no steering angles"
        if len(a) == 1:
            return f"1 steering-wheel angle, {a[0]:+.1f}°"
        return f"{len(a)} steering-wheel angles, {a[0]:+.1f}° to {a[-1]:+.1f}°"

    def summary_text(self, table_name: str) -> str:
        """One line of plain text: the table ``table_name``, its SHA-256 and the angles, or
        "no guidelines: <reason>"."""
        if self.reason is not None:
            return f"{NO_GUIDELINES}: {self.reason}"
        return f"{table_name} sha256 {self.sha256}; {self.angles_text()}"

    def as_dict(self, file: str) -> dict[str, Any]:
        """What signoff.json records: the table ``file`` (its path), format, size, SHA-256
        and the angles (degrees), or the reason there are none."""
        if self.reason is not None:
            return {"none": self.reason}
        assert self.output is not None
        return {"file": file, "format": f"RVMG {TABLE_VERSION}", "bytes": len(self.table),
                "sha256": self.sha256, "steering_deg": list(self.steering_deg),
                "shown_deg": self.shown_deg, "lines": self.lines,
                "lines_shown": self.lines_shown, "covers": dict(self.covers),
                "output": [self.output.width, self.output.height, self.output.mirror]}


def _reason(err: RvmsimError) -> str:
    """A scene's problem in one line without its file (the page names the scene)."""
    if isinstance(err, InputFileError):
        return f"{err.key}: {err.message}" if err.key else err.message
    return str(err)


def _points(line: DisplayLine) -> int:
    return sum(len(p.uv_px) for p in line.pieces)


def _row(line: DisplayLine) -> GuidelineRow:
    return GuidelineRow(line.name, line.kind, line.steering_deg, line.shown, _points(line))


def guideline_figures(scene: Scene, params: IspParams, output: OutputSpec,
                      images: FisheyeImages, *,
                      shown: tuple[OutputSpec, np.ndarray] | None = None) -> GuidelineFigures:
    """A setting's guidelines for a page: pictures, lines and the ECU table.

    Parameters
    ----------
    scene : Scene
        The car (its ``vehicle`` with the running gear) and the camera at its mount.
    params : IspParams
        The setting.
    output : OutputSpec
        The tuning output: its mirroring is kept; the size is the scene's image of record
        (:func:`rvmsim.guidelines.guideline_output`).
    images : FisheyeImages
        The scene's fisheye render, for the RVM picture.
    shown : (OutputSpec, ndarray), optional
        An RVM colour picture already made of ``params`` at that output: used when that
        output is the image of record, instead of running the ISP again.

    Returns
    -------
    GuidelineFigures
        With ``reason`` set (and nothing else) when the scene lacks what the guidelines
        need; the table covers the car's whole steering range in 10° steps plus its ends
        (:func:`rvmsim.guidelines.steering_angles`).
    """
    try:
        angles = steering_angles(running_gear(scene))
        view = guideline_view(scene, params, output)
        gset = compute_guidelines(scene, view, angles)
    except RvmsimError as err:
        return GuidelineFigures(reason=_reason(err))
    record = view.output
    rvm = shown[1] if shown is not None and shown[0] == record else rvm_color(images, params,
                                                                                record)
    width = gset.spec.line_width_px
    deg = shown_angle(gset)
    picture = draw_lines(rvm, gset.at(deg), width)
    ends = sorted({min(gset.steering_deg), max(gset.steering_deg)} - {deg})
    ends_lines = [line for a in ends for line in gset.trajectories[gset.steering_deg.index(a)]]
    extremes = None
    if len(gset.steering_deg) > 1:
        extremes = draw_lines(rvm, [*gset.static, *ends_lines], width)
    rows = [_row(line) for line in gset.at(deg)] + [_row(line) for line in ends_lines]
    every = gset.lines()
    return GuidelineFigures(
        reason=None, output=record, steering_deg=tuple(sorted(gset.steering_deg)),
        shown_deg=deg, picture=picture, extremes=extremes, rows=tuple(rows),
        lines=len(every), lines_shown=sum(1 for line in every if line.shown),
        table=table_bytes(gset), covers=required_coverage(scene, gset, images.labels))


def guideline_table_name(page_file: str | Path) -> str:
    """The table's file name beside the page ``page_file``: :data:`GUIDELINE_TABLE` beside
    a ``report.html``, else ``<page name>.guidelines.bin`` (two pages written into one
    folder do not share a table their hashes disagree on)."""
    stem = Path(page_file).stem
    return GUIDELINE_TABLE if stem == "report" else f"{stem}.{GUIDELINE_TABLE}"


def _angle_text(deg: float | None) -> str:
    return "static" if deg is None else f"{deg:+.1f}°"


_OFF = ' class="off"'


def _lines_table(fig: GuidelineFigures) -> str:
    head = ("<tr><th>line</th><th>kind</th><th>steering</th><th>shown</th>"
            "<th>points</th></tr>")
    rows = "".join(
        f'<tr{"" if r.shown else _OFF}><td class="nobr">{escape(r.name)}</td>'
        f"<td>{escape(r.kind)}</td><td class=\"num\">{escape(_angle_text(r.steering_deg))}"
        f'</td><td>{"yes" if r.shown else "no"}</td><td class="num">{r.points}</td></tr>'
        for r in fig.rows)
    return f"<table>{head}{rows}</table>"


def _table_facts(fig: GuidelineFigures, file_html: str) -> str:
    rows = [("ECU table", file_html),
            ("format", f"RVMG version {TABLE_VERSION}; layout in rvmsim.guidelines.table"),
            ("size", f"{len(fig.table)} bytes"),
            ("SHA-256", sha_html(fig.sha256)),
            ("steering angles covered", escape(fig.angles_text())),
            ("lines", f"{fig.lines} ({fig.lines_shown} shown on the picture)")]
    return "<table>" + "".join(f"<tr><th>{a}</th><td>{b}</td></tr>" for a, b in rows) \
        + "</table>"


def guidelines_html(fig: GuidelineFigures, table_name: str, *, link: bool = True,
                    heading: str = "Parking guidelines") -> str:
    """The "Parking guidelines" section (id ``guidelines``): the pictures, the ECU table's
    file (``table_name``, beside the page; a link when ``link``), size, SHA-256 and angles,
    and the lines; or the line saying why there are none."""
    open_ = f'<section id="guidelines"><h2>{escape(heading)}</h2>'
    if fig.reason is not None:
        return (f'{open_}<p class="warn">{NO_GUIDELINES}: {escape(fig.reason)}</p>'
                "</section>")
    assert fig.picture is not None and fig.output is not None
    o = fig.output
    name = escape(table_name)
    file_html = (f'<a href="{escape(url_path(table_name))}"><code>{name}</code></a>' if link
                 else f"<code>{name}</code>") + " (beside this page)"
    figs = [f"<figure>{img_tag(fig.picture, 'guidelines straight ahead', PICTURE_MAX_PX)}"
            f"<figcaption>The RVM image of record ({o.width} × {o.height} px) with the "
            f"static lines and the trajectory at {fig.shown_deg:+.1f}° "
            "(straight ahead).</figcaption></figure>"]
    if fig.extremes is not None:
        a = fig.steering_deg
        figs.append(f"<figure>{img_tag(fig.extremes, 'guidelines at full lock', EXTREMES_MAX_PX)}"
                    f"<figcaption>The trajectories at both ends of the steering range "
                    f"({a[0]:+.1f}° and {a[-1]:+.1f}°, ±100 %).</figcaption></figure>")
    return (f'{open_}<p class="muted">The car\'s parking guidelines through this setting '
            "(distance marks, width lines, trajectory lines per steering angle), and the "
            "table a camera ECU loads; its SHA-256 is of exactly the file named.</p>"
            f"{''.join(figs)}{_table_facts(fig, file_html)}{_covers_html(fig)}"
            f"<h3>Lines</h3>{_lines_table(fig)}</section>")


def _covers_html(fig: GuidelineFigures) -> str:
    """Which test objects' required-visible areas the lines are drawn over (FMVSS 111's,
    UN R158's), or that they cover none."""
    rows = []
    for site, objs in fig.covers.items():
        for name, v in objs.items():
            rows.append(f"<tr><td>{escape(site)}</td><td>{escape(name)}</td>"
                        f"<td>{escape(covered_by(v))}</td>"
                        f'<td class="num">{100 * v["fraction"]:.1f} %</td></tr>')
    if not rows:
        return ('<p>The lines cover none of the test objects\' required-visible '
                "areas (FMVSS 111, UN R158).</p>")
    return ("<h3>Required-visible areas the lines are drawn over</h3>"
            '<p class="muted">UN R158 allows reversing information over the field of vision; '
            "these are the test objects whose required areas a line covers (up to the share "
            "of the area shown).</p><table><tr><th>site</th><th>object</th><th>by</th>"
            f"<th>covered</th></tr>{''.join(rows)}</table>")


def guidelines_summary_html(fig: GuidelineFigures, table_name: str) -> str:
    """One line for a summary: the table's file, SHA-256 and angles, or why there is none."""
    if fig.reason is not None:
        return f"{NO_GUIDELINES}: {escape(fig.reason)}"
    return (f"<code>{escape(table_name)}</code> sha256 {sha_html(fig.sha256)}; "
            f"{escape(fig.angles_text())}")
