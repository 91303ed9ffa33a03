"""What the console writes, always inside its session's folder: params files (the format
``rvmsim select`` writes) and review reports of one setting (the report kit of
:mod:`rvmsim.report`).

File names are made here (a time stamp, an optional sanitised label, a counter), never
taken from the browser, and every file is created exclusively: nothing is overwritten.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import yaml

from ..errors import RvmsimError
from ..isp import PARAM_SPECS, draw_roi, params_to_dict
from ..report import ec_section
from ..report.page import escape, img_tag, page
from ..pipeline import evaluate_params, rvm_color
from .session import ConsoleFrame

if TYPE_CHECKING:
    from ..isp import IspParams
    from .session import ConsoleSession

__all__ = ["save_params", "write_setting_report", "params_text", "setting_page"]


def _new_file(session: ConsoleSession, stem: str, label: str, suffix: str, text: str) -> Path:
    """Create ``save_dir/<stem>_<time>[_<label>][_<k>]<suffix>`` holding ``text``; the path
    is checked to lie inside the session's root (a symlinked ``console`` folder pointing
    elsewhere is refused)."""
    root = session.root.resolve()
    try:
        session.save_dir.mkdir(parents=True, exist_ok=True)
        folder = session.save_dir.resolve()
        if not folder.is_relative_to(root):
            raise RvmsimError(f"{session.save_dir}: outside {session.root}; not writing there")
        base = f"{stem}_{time.strftime('%Y%m%d-%H%M%S')}" + (f"_{label}" if label else "")
        for k in range(1, 1000):
            path = folder / (base + ("" if k == 1 else f"_{k}") + suffix)
            try:
                with open(path, "x", encoding="utf-8") as f:
                    f.write(text)
                return path
            except FileExistsError:
                continue  # taken (two saves in one second): the next counter
    except OSError as err:
        raise RvmsimError(f"{session.save_dir}: cannot write ({err.strerror or err})") from None
    raise RvmsimError(f"{session.save_dir}: too many files named {base}*{suffix}")


def params_text(session: ConsoleSession, frame: ConsoleFrame, label: str) -> str:
    """A params file as ``rvmsim select`` writes it (comment lines, then the 14 parameters,
    the run's search output and the size of record the ECs were judged at), loadable by
    :func:`rvmsim.isp.load_params`."""
    what = f" '{label}'" if label else ""
    result = "all pass" if frame.ec.passed else "not all pass"
    rec = session.ec_output
    return (f"# console setting{what} of {session.scene.name}: EC score {frame.ec.score:.6g} "
            f"({result}; from {session.kind} {session.source})\n"
            f"# judged at the RVM image of record, {rec.width}x{rec.height} px\n"
            + yaml.safe_dump(params_to_dict(frame.params, session.search_output or rec,
                                            judged_at=rec), sort_keys=False))


def save_params(session: ConsoleSession, frame: ConsoleFrame, label: str = "") -> Path:
    """Write ``frame``'s parameters as a new params file in the session's ``console/``
    folder; returns its path."""
    return _new_file(session, "params", label, ".yaml", params_text(session, frame, label))


def _params_table(session: ConsoleSession, params: IspParams) -> str:
    tuned = {c.name for c in session.controls if c.tuned}
    head = ("<tr><th>parameter</th><th>paper name</th><th>value</th><th>start</th>"
            "<th>unit</th><th>tuned</th></tr>")
    rows = "".join(
        f'<tr class="{"tuned" if s.name in tuned else ""}"><td>{escape(s.name)}</td>'
        f"<td>{escape(s.paper_name)}</td><td class=\"num\">{getattr(params, s.name):.6g}</td>"
        f'<td class="num">{getattr(session.start, s.name):.6g}</td><td>{escape(s.unit)}</td>'
        f'<td>{"yes" if s.name in tuned else "no"}</td></tr>' for s in PARAM_SPECS)
    return f'<section id="params"><h2>ISP parameters</h2><table>{head}{rows}</table></section>'


def setting_page(session: ConsoleSession, frame: ConsoleFrame, annotated: np.ndarray,
                 color: np.ndarray) -> str:
    """The review page of one setting: scene, images, EC table, parameters."""
    sc = session.scene
    rows = [("Vehicle", sc.name), ("Description", sc.description or "—"),
            ("Scene file", str(session.scene_file)), ("Console of", f"{session.kind} "
                                                                    f"{session.source}"),
            ("Criteria", session.criteria.name),
            ("EC image", f"{session.ec_output.width} × {session.ec_output.height} px")]
    scene = "".join(f"<tr><th>{escape(a)}</th><td>{escape(b)}</td></tr>" for a, b in rows)
    roi = draw_roi(session.images.color, frame.params, session.ec_output, thickness=3)
    figs = "".join(f"<figure>{img}<figcaption>{escape(cap)}</figcaption></figure>" for img, cap in (
        (img_tag(roi, "fisheye input with ROI", 640), "Fisheye image; green: the ROI."),
        (img_tag(color, "RVM image"), "RVM image at the display size."),
        (img_tag(annotated, "annotated EC image", 1200), "The ECs measured on the RVM image.")))
    badge = "pass" if frame.ec.passed else "fail"
    body = (f"<h1>{escape(sc.name)}</h1><p>RVM setting review (rvmsim console) — EC score "
            f'<b>{frame.ec.score:.4g}</b> <span class="badge {badge}">'
            f'{"all ECs pass" if frame.ec.passed else "not all pass"}</span></p>'
            f'<section id="scene"><h2>Scene summary</h2><table>{scene}</table></section>'
            f'<section id="images"><h2>Images</h2>{figs}</section>'
            + ec_section(frame.ec) + _params_table(session, frame.params))
    return page(f"RVM setting review: {sc.name}", body)


def write_setting_report(session: ConsoleSession, params: IspParams, label: str = "") -> Path:
    """Write a review report of ``params`` (self-contained HTML) as a new file in the
    session's ``console/`` folder; returns its path."""

    full = evaluate_params(session.images, params, session.ec_output, session.criteria)
    frame = ConsoleFrame(params, full.ec, b"", None, [], {})
    color = rvm_color(session.images, params, session.display)
    assert full.annotated is not None  # asked for (evaluate_params annotates by default)
    text = setting_page(session, frame, full.annotated, color)
    return _new_file(session, "report", label, ".html", text)
