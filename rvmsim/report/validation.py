"""The validation page: one self-contained HTML page for a scene validated against a capture.

Verdict table, pose correction with σ, the terminal summary and the pictures (PNG data
URIs), built with the page kit (:mod:`.page`).  Every string from a user's files (scene
name, capture path) is HTML-escaped.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

from ..errors import RvmsimError
from ..storage import json_default, staged_folder, write_text
from ..validate import CaptureOutcome, Validation, write_pictures
from .page import escape, img_tag, page

__all__ = ["validation_page", "write_validation_outputs", "PICTURE_CAPTIONS",
           "SUMMARY_COLUMNS", "summary_table", "write_validation_summary", "summary_page"]

#: Caption of each validation picture, by file stem.
PICTURE_CAPTIONS: dict[str, str] = {
    "landmarks": "Landmarks: predicted from the scene (red +, error line drawn 5× long), "
                 "found (green o), outliers (orange x), after correction (cyan dot)",
    "overlay": "Capture and synthetic frame blended (scene's pose)",
    "overlay_corrected": "Capture and synthetic frame blended (corrected pose)",
    "edges": "Edges: capture green, synthetic magenta, both white (scene's pose)",
    "edges_corrected": "Edges after the pose correction",
    "rvm_capture": "Capture through the ISP",
    "rvm_synthetic": "Synthetic frame through the ISP",
    "rvm_overlay": "RVM images blended",
    "rvm_edges": "RVM edges: capture green, synthetic magenta",
}

#: Longest side of an embedded picture, px.
PICTURE_MAX_PX = 960


def validation_page(result: Validation) -> str:
    """The whole HTML document for ``result``: verdict, numbers, pictures."""
    return page(f"Validation: {result.scene_name}", _validation_body(result, 1))


def _validation_body(result: Validation, level: int) -> str:
    """The sections of one validation, headings from ``<h{level}>`` down."""
    verdict = "PASS" if result.passed else "FAIL"
    h1, h2 = f"h{level}", f"h{level + 1}"
    return f"""
<{h1}>Validation of {escape(result.scene_name)} against {escape(result.capture)}: {verdict}</{h1}>
<p>Capture: {escape(result.capture)}, {result.image_size[0]}×{result.image_size[1]} px.
{result.n_inliers} landmarks matched ({result.n_found} found,
{result.n_predicted} predicted visible). Start: {escape(result.start)}.</p>
<{h2}>Verdict</{h2}><table><tr><th>check</th><th>value</th><th>limit</th><th></th>
<th>what to fix</th></tr>{_check_rows(result)}</table>
<{h2}>Pose correction</{h2}><table><tr><th></th><th>change</th><th>σ</th><th></th></tr>{_pose_rows(result)}
</table>
<pre>{escape(result.summary())}</pre>
<{h2}>Pictures</{h2}>{_figures(result.images)}
"""


def _check_rows(result: Validation) -> str:
    return "".join(
        f'<tr class="{"pass" if k.passed else "fail"}"><td>{escape(k.name)}</td>'
        f"<td>{k.value:.3g}</td><td>≤ {k.limit:g}</td><td>{'pass' if k.passed else 'FAIL'}"
        f"</td><td>{'' if k.passed else escape(k.hint)}</td></tr>"
        for k in result.checks
    )


def _pose_rows(result: Validation) -> str:
    c = result.correction
    return "".join(
        f"<tr><td>{escape(n)}</td><td>{v:+.2f}</td><td>± {s:.2f}</td><td>{escape(u)}</td></tr>"
        for n, v, s, u in (
            ("Δx (driver side)", c.d_position_mm[0], c.sigma_position_mm[0], "mm"),
            ("Δy (down)", c.d_position_mm[1], c.sigma_position_mm[1], "mm"),
            ("Δz (rearward)", c.d_position_mm[2], c.sigma_position_mm[2], "mm"),
            ("Δyaw", c.d_yaw_deg, c.sigma_angles_deg[0], "°"),
            ("Δpitch", c.d_pitch_deg, c.sigma_angles_deg[1], "°"),
            ("Δroll", c.d_roll_deg, c.sigma_angles_deg[2], "°"),
        )
    )


def _figures(images: dict[str, np.ndarray]) -> str:
    return "".join(
        f"<figure>{img_tag(img, name, PICTURE_MAX_PX)}<figcaption>"
        f"{escape(PICTURE_CAPTIONS.get(name, name))}</figcaption></figure>"
        for name, img in images.items()
    )


def write_validation_outputs(result: Validation, out_dir: str | Path) -> list[Path]:
    """Write ``validation.json``, ``validation.html`` and the PNGs into ``out_dir``.

    Returns
    -------
    list of Path
        ``validation.json``, ``validation.html``, then one PNG per picture (file stem =
        key of ``result.images``).

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    out = Path(out_dir)
    js, html_path = out / "validation.json", out / "validation.html"
    with staged_folder(out) as stage:  # moved in when all is written
        paths = [out / p.name for p in write_pictures(result.images, stage)]
        write_text(stage / js.name,
                   json.dumps(result.to_dict(), indent=2, default=json_default) + "\n")
        write_text(stage / html_path.name, validation_page(result))
    return [js, html_path, *paths]


#: Columns of the summary table, in order.
SUMMARY_COLUMNS = ("capture", "verdict", "step_failed", "inliers", "predicted",
                   "rms_before_px", "rms_after_px", "d_position_mm", "max_d_angle_deg",
                   "error", "out_dir")


def summary_table(outcomes: list[CaptureOutcome]) -> str:
    """The summary as fixed-width text for the terminal, one line per capture."""
    def num(v: object, fmt: str) -> str:
        return "-" if v is None else format(v, fmt)

    lines = [f"{'capture':<40} {'verdict':<7} {'inliers':>7} {'RMS px':>7} {'Δpos mm':>8} "
             f"{'Δangle°':>8}  step failed"]
    for o in outcomes:
        r = o.row()
        lines.append(f"{o.capture[-40:]:<40} {o.verdict:<7} {num(r['inliers'], 'd'):>7} "
                     f"{num(r['rms_after_px'], '.2f'):>7} {num(r['d_position_mm'], '.1f'):>8} "
                     f"{num(r['max_d_angle_deg'], '.3f'):>8}  {o.step}")
    return "\n".join(lines)


def write_validation_summary(outcomes: list[CaptureOutcome], out_dir: str | Path) -> list[Path]:
    """Write ``summary.json``, ``summary.csv`` and ``validation.html`` (one page: the table,
    then every capture's validation or failure with its pictures) into ``out_dir``.

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    out = Path(out_dir)
    rows = [o.row() for o in outcomes]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=SUMMARY_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    paths = [out / "summary.json", out / "summary.csv", out / "validation.html"]
    with staged_folder(out) as stage:  # moved in when all is written (captures' folders kept)
        write_text(stage / paths[0].name, json.dumps(rows, indent=2, default=json_default) + "\n")
        write_text(stage / paths[1].name, buf.getvalue())
        write_text(stage / paths[2].name, summary_page(outcomes))
    return paths


def summary_page(outcomes: list[CaptureOutcome]) -> str:
    """One HTML document for several captures: the summary table, then each capture."""
    head = "".join(f"<th>{escape(c)}</th>" for c in SUMMARY_COLUMNS if c != "out_dir")
    body = "".join(
        f'<tr class="{"pass" if o.verdict == "PASS" else "fail"}">' + "".join(
            f"<td>{escape(_cell(v))}</td>" for k, v in o.row().items() if k != "out_dir")
        + "</tr>" for o in outcomes)
    sections = "".join(
        _validation_body(o.result, 2) if o.result is not None else
        f"<h2>{escape(o.capture)}: ERROR</h2><p>{escape(o.error)}</p>{_figures(o.images)}"
        for o in outcomes)
    n_pass = sum(o.verdict == "PASS" for o in outcomes)
    return page("Validation of several captures", f"""
<h1>Validation: {n_pass} of {len(outcomes)} captures pass</h1>
<table><tr>{head}</tr>{body}</table>{sections}""")


def _cell(v: object) -> str:
    if v is None:
        return "-"
    return f"{v:.3g}" if isinstance(v, float) else str(v)
