"""Review reports: one self-contained HTML page per tuning run, and an index for a batch.

A report shows what a tuning run found, for engineers reviewing it with colleagues and
customers: the scene (vehicle, camera, lens, mount, criteria), the fisheye image with the
ROI of the chosen parameters, the RVM image and the annotated EC image, the EC table, the
parameter table, the convergence of the search, and the diverse top-M candidates (each with
how it differs from rank 1, :mod:`rvmsim.runs.diverse`) so the expert can make the final
choice (``rvmsim select RUN --rank K`` exports any of them).

Everything is embedded (PNG images as ``data:`` URIs, CSS in a ``<style>`` element); the page
needs no network, fonts or scripts.  Every string that comes from a user's files (vehicle
name, description, file names, criteria name) is HTML-escaped.

Sections carry stable ids: ``scene``, ``images``, ``ec-table``, ``guidelines``, ``params``,
``convergence``, ``gallery``.

The ``guidelines`` section shows rank 1's parking guidelines (:mod:`.guidelines`): the
pictures, the lines and the ECU table's SHA-256; the table itself is written beside the page
(``guidelines.bin`` beside ``report.html``), with it or not at all.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._progress import progress_bar
from ..errors import RvmsimError
from ..storage import StagedFiles, write_problem, write_text
from ..pipeline import evaluate_params, record_output, rvm_color
from ..runs import (open_run, recorded_path, run_inputs, run_settings, run_state,
                    store_candidates, top_file)
from ..tune import member_set
from ..tune.markets import load_markets
from .market_rows import markets_html
from .members import (MemberScene, load_member_scenes, member_scores_html, members_section,
                      robust_section)
from .page import data_uri, escape, img_tag, page, shrink
from .gallery import differences, margins_html
from .guidelines import GUIDELINE_TABLE, guideline_figures, guideline_table_name, guidelines_html
from .plots import convergence_png, histogram_png
from .provenance import provenance
from .run_notes import display_figure, provenance_line, signoff_note, yield_note
from ..criteria import load_criteria
from ..criteria.canvas import unit_text
from ..render import cached_render, same_scene
from ..scene import load_scene
from ..isp import PARAM_SPECS, IspParams, draw_roi

if TYPE_CHECKING:
    from ..tune.robust import RobustSummary
    from ..criteria import Criteria, EcResult, EcValue
    from ..isp import OutputSpec
    from ..render import FisheyeImages
    from ..scene import Scene
    from ..runs import Candidate, RunSettings, RunState, TrialRecord
    from ..search import TuningConfig

__all__ = ["write_report", "EC_GROUP_NAMES",
           "SECTION_IDS", "ec_section"]

#: The paper groups the ECs by their first digit.
EC_GROUP_NAMES: dict[str, str] = {
    "1": "FMVSS 111 visibility",
    "2": "bumper / body",
    "3": "guidelines",
    "4": "calibration board",
}

#: The ids of a run report's sections, in page order.
SECTION_IDS: tuple[str, ...] = ("scene", "images", "ec-table", "guidelines", "params",
                                "convergence", "gallery")

#: Longest side of the embedded fisheye image, gallery thumbnails and index thumbnails (px).
FISHEYE_MAX_PX = 640
GALLERY_MAX_PX = 320
INDEX_THUMB_PX = 192


# ---------------------------------------------------------------------------- run data
@dataclass
class _Run:
    """Everything a report shows, read from a run folder."""

    run_dir: Path
    settings: RunSettings
    state: RunState
    scene_file: Path
    scene: Scene
    images: FisheyeImages
    config: TuningConfig
    criteria: Criteria
    criteria_file: Path | None
    output: OutputSpec
    top: list[TrialRecord]
    curve: list[tuple[int, float, str]]
    scores: np.ndarray
    count: int
    scene_changed: bool = False
    members: list[MemberScene] = field(default_factory=list)
    member_top: dict[int, list[float]] = field(default_factory=dict)
    robust_rows: list[RobustSummary | None] = field(default_factory=list)
    candidates: list[Candidate] = field(default_factory=list)


def _load_run(run_dir: Path) -> _Run:
    store = open_run(run_dir)
    try:
        settings = run_settings(run_dir, store)
        kind = member_set(settings)
        scene_file, crit_file = run_inputs(run_dir, settings)
        own = load_scene(scene_file)  # as the run recorded it (its key is this one's)
        scene, criteria = kind.shown(own, load_criteria(crit_file))
        state = run_state(run_dir, store)
        pairs = store_candidates(store, settings, criteria=criteria)
        top = [rec for _, rec in pairs]
        curve = store.best_curve()
        scores = np.array(store.scores(), dtype=float)
        count = store.count()
        rows = kind.top_rows(store, top)  # what the run's kind says of each
    finally:
        store.close()
    if not top:
        raise RvmsimError(f"{run_dir}: no evaluated candidates to report yet")
    images, _ = cached_render(scene)
    recorded_key = settings.scene_key
    scene_changed = recorded_key is not None and not same_scene(recorded_key, own, scene_file)
    return _Run(run_dir, settings, state, scene_file, scene, images, settings.config, criteria,
                crit_file, settings.record_output(), top, curve, scores, count,
                scene_changed, load_member_scenes(settings, run_dir, recorded_path),
                rows.member_scores, rows.robust, [c for c, _ in pairs])


# ---------------------------------------------------------------------------- sections
def _fmt(x: float | None, digits: int = 4) -> str:
    if x is None:
        return "—"
    return f"{x:.{digits}g}"


def _status(item: EcValue) -> str:
    return "off" if not item.enabled else ("pass" if item.passed else "fail")


def _scene_section(r: _Run) -> str:
    sc = r.scene
    cam = sc.fisheye_camera()
    lens = sc.camera.lens
    m = sc.camera.mount
    k = ", ".join(f"{v:g}" for v in (lens.k or (0.0, 0.0, 0.0, 0.0)))
    rows = [
        ("Vehicle", sc.name),
        ("Description", sc.description or "—"),
        ("Scene file", str(r.scene_file)),
        ("Image size", f"{cam.width} × {cam.height} px"),
        ("Intrinsics", f"fx {cam.fx:.2f}, fy {cam.fy:.2f} px/rad; cx {cam.cx:.2f}, "
                       f"cy {cam.cy:.2f} px; skew {cam.skew:g}"),
        ("Lens model", f"{lens.model}, field of view {lens.fov_deg:g}°"
                       + (f", k = [{k}]" if lens.k is not None else "")),
        ("Mount position", "({:g}, {:g}, {:g}) m".format(*m.position)),
        ("Mount angles", f"yaw {m.yaw_deg:g}°, pitch {m.pitch_deg:g}°, roll {m.roll_deg:g}°"),
        ("Criteria", f"{r.criteria.name} — "
                     + (str(r.criteria_file) if r.criteria_file else "built-in (paper thresholds)")),
        ("Search", f"{r.settings.strategy}, seed {r.settings.seed}, "
                   f"{r.count} evaluations, status {r.state.text}"),
        ("Run folder", str(r.run_dir)),
    ]
    body = "".join(f"<tr><th>{escape(a)}</th><td>{escape(b)}</td></tr>" for a, b in rows)
    return f'<section id="scene"><h2>Scene summary</h2><table>{body}</table></section>'


def _images_section(r: _Run, color: np.ndarray, annotated: np.ndarray) -> str:
    """The fisheye with the ROI, the RVM picture at the tuning size and at the display's,
    and the annotated EC image."""

    roi = draw_roi(r.images.color, r.top[0].params, r.output, thickness=3)
    figs = [
        (img_tag(roi, "fisheye input with ROI", FISHEYE_MAX_PX),
         "Fisheye input image; the green outline is the region the RVM image shows under "
         "the chosen parameters (paper, Table 4)."),
        (img_tag(color, "RVM colour image"),
         f"RVM image ({r.output.width} × {r.output.height} px, "
         f"{'mirrored' if r.output.mirror else 'not mirrored'})."),
        (img_tag(annotated, "annotated EC image", 1200),
         "The ECs measured on the RVM image (paper, Fig. 17–20)."),
    ]
    body = "".join(f"<figure>{img}<figcaption>{escape(cap)}</figcaption></figure>"
                   for img, cap in figs)
    display = display_figure(r.images, r.top[0].params,
                             record_output(r.criteria, r.scene, r.output.mirror))
    return f'<section id="images"><h2>Images</h2>{body}{display}</section>'


def _ec_section(result: EcResult) -> str:
    head = ("<tr><th>EC</th><th>measurement</th><th>value</th><th>unit</th>"
            "<th>acceptable range</th><th>margin</th><th>score</th><th>result</th></tr>")
    rows = []
    for i in result.items:
        st = _status(i)
        rng = f"[{_fmt(i.low)}, {_fmt(i.high)}]" if (i.low is not None or i.high is not None) \
            else "= 1"
        rows.append(
            f'<tr class="{st}"><td>{escape(i.id)}</td><td>{escape(i.name)}</td>'
            f'<td class="num">{escape(_fmt(i.value))}</td><td>{escape(i.unit)}</td>'
            f'<td class="num">{escape(rng)}</td>'
            f'<td class="num">{escape(i.margin_text(unit_text(i.unit)))}</td>'
            f'<td class="num">{i.score:.4f}</td>'
            f'<td>{escape(st)}</td></tr>')
    badge = "pass" if result.passed else "fail"
    summary = (f'<p>EC score <b>{result.score:.4g}</b> '
               f'<span class="badge {badge}">{"all ECs pass" if result.passed else "not all pass"}'
               f'</span> <span class="muted">criteria: {escape(result.criteria_name)}</span></p>')
    return (f'<section id="ec-table"><h2>Evaluation criteria</h2>{summary}'
            f'<table>{head}{"".join(rows)}</table><p class="muted">Margin: the signed '
            "distance of the value inside its range, in the EC's unit (below 0 fails).</p>"
            "</section>")


#: The EC table section, public for the console's setting report.
ec_section = _ec_section


def _params_section(r: _Run) -> str:
    space = r.config.space(r.scene.fisheye_camera())
    tuned = {pr.name: pr for pr in space.ranges}
    chosen = r.top[0].params
    default = IspParams()
    head = ("<tr><th>parameter</th><th>paper name</th><th>chosen</th><th>default</th>"
            "<th>range</th><th>unit</th><th>tuned</th></tr>")
    rows = []
    for spec in PARAM_SPECS:
        pr = tuned.get(spec.name)
        if pr is not None:
            rng = f"[{pr.low:g}, {pr.high:g}] (search)"
        else:
            rng = f"[{spec.low:g}, {spec.high:g}] (Table 2)"
        fixed = "" if pr is not None or spec.name not in r.config.fixed else " (fixed)"
        rows.append(
            f'<tr class="{"tuned" if pr is not None else ""}"><td>{escape(spec.name)}</td>'
            f'<td>{escape(spec.paper_name)}</td>'
            f'<td class="num">{getattr(chosen, spec.name):.6g}</td>'
            f'<td class="num">{getattr(default, spec.name):g}</td>'
            f'<td class="num">{escape(rng)}</td><td>{escape(spec.unit)}</td>'
            f'<td>{"yes" if pr is not None else "no" + fixed}</td></tr>')
    return (f'<section id="params"><h2>ISP parameters</h2>'
            f'<p class="muted">{len(tuned)} of {len(PARAM_SPECS)} parameters tuned (bold); '
            f'the chosen values are those of rank 1.</p>'
            f'<table>{head}{"".join(rows)}</table></section>')


def _convergence_section(r: _Run) -> str:
    conv = data_uri(convergence_png(r.curve))
    hist = data_uri(histogram_png(r.scores))
    return ('<section id="convergence"><h2>Convergence</h2>'
            f'<figure><img src="{conv}" alt="convergence plot"><figcaption>Best EC score so '
            'far vs evaluations, coloured by search stage.</figcaption></figure>'
            f'<figure><img src="{hist}" alt="score histogram"><figcaption>EC scores of all '
            'trials (log-spaced bins).</figcaption></figure></section>')


def _gallery_section(r: _Run, run_arg: str, best_color: np.ndarray) -> str:
    """The top-M cards; ``best_color`` is rank 1's RVM image, already made for the page."""

    cards = []
    first = r.top[0]
    for cand, rec in zip(r.candidates, r.top):
        k = cand.rank
        color = best_color if k == 1 else rvm_color(r.images, rec.params, r.output)
        diffs = differences(rec, first, r.criteria)
        if k == 1:
            diff_html = "<p class='muted'>reference (rank 1)</p>"
        else:
            diff_html = (f'<p class="differs">{escape(cand.differs)} <span class="muted">'
                         f'(distance {cand.distance:.2f})</span></p>')
            if diffs:
                diff_html += "<ul>" + "".join(f"<li>{escape(d)}</li>" for d in diffs) + "</ul>"
        badge = "pass" if rec.passed else "fail"
        kept = top_file(r.run_dir, k, rec.params, r.config.output_spec())
        export = (f'<p>Its params file: <code>{escape(f"{run_arg}/top/{kept.name}")}</code></p>'
                  if kept is not None else
                  "<p>Export: <code>" + escape(f"rvmsim select {shlex.quote(run_arg)} --rank {k} "
                                              f"--out rank_{k}.yaml") + "</code></p>")
        cards.append(
            f'<div class="card{" rank1" if k == 1 else ""}" id="rank-{k}">'
            f'<h3>#{k} <span class="badge {badge}">{badge}</span></h3>'
            f'{img_tag(color, f"rank {k} RVM image", GALLERY_MAX_PX)}'
            f'<p>EC score <b>{rec.score:.4g}</b> <span class="muted">trial {rec.idx} '
            f'({escape(rec.stage)})</span></p>'
            f'{margins_html(cand.margins, rec, r.criteria)}'
            f'{member_scores_html(r.members, r.member_top.get(rec.idx, []))}{diff_html}'
            f'{export}</div>')
    dmin = r.config.diverse.min_distance
    return (f'<section id="gallery"><h2>Top-{len(r.top)} candidates</h2>'
            '<p class="muted">Genuinely different candidates for the final choice: after #1 '
            '(the best trial), the all-pass trials farthest from those already shown, each '
            f'at least {dmin:g} of the search span from every other (docs/tuning.md, "The '
            'diverse top-M"). Each card shows every EC\'s margin (how far its value is '
            'inside its range, in the EC\'s unit; red: outside), how it differs from #1 and '
            'which ECs change result; choose one: its params file is in the run\'s top/ '
            'folder.</p>'
            f'<div class="gallery">{"".join(cards)}</div></section>')


def _group_status(result: EcResult) -> dict[str, str]:
    """'pass', 'fail' or 'off' per EC group (the first digit of the EC id)."""
    out = {}
    for g in EC_GROUP_NAMES:
        items = [i for i in result.items if i.id.split("-")[0] == g and i.enabled]
        out[g] = "off" if not items else ("pass" if all(i.passed for i in items) else "fail")
    return out


@dataclass(frozen=True)
class _Summary:
    """What the batch index shows of one run."""

    vehicle: str
    score: float
    passed: bool
    groups: dict[str, str]
    thumb: np.ndarray
    #: Files to write beside the page, by name (the guidelines' ECU table).
    files: dict[str, bytes] = field(default_factory=dict)


#: The steps of one run's report, as its progress bar counts them.
_STEPS = 4


def _build(run_dir: Path, report_dir: Path | None = None, bar: Any = None,
           table_name: str = GUIDELINE_TABLE) -> tuple[str, _Summary]:
    """The report page of one run (to be written into ``report_dir``, default the run
    folder: links are relative to it), and the summary the batch index shows (with the
    files to write beside the page: the guidelines' table as ``table_name``); ``bar`` (a
    progress bar) advances by :data:`_STEPS`."""

    def step(next_step: str) -> None:
        if bar is not None:
            bar.update()
            bar.set_postfix_str(next_step)

    if bar is not None:
        bar.set_postfix_str("reading the run")
    r = _load_run(run_dir)
    report_dir = report_dir if report_dir is not None else run_dir
    step("the ECs of rank 1")
    frame = evaluate_params(r.images, r.top[0].params, r.output, r.criteria)
    result, color, annotated = frame.ec, frame.color, frame.annotated
    assert annotated is not None
    badge = "pass" if result.passed else "fail"
    markets = load_markets(run_dir)
    sections = (("markets",) if markets else ()) + (("members",) if r.members else ()) + (("robust",) if r.robust_rows else ()) \
        + SECTION_IDS
    title = (r.scene.name if not r.members
             else "shared: " + ", ".join(m.vehicle for m in r.members))
    header = (f"<h1>{escape(title)}</h1>"
              f'<p>RVM tuning review — EC score <b>{result.score:.4g}</b> '
              f'<span class="badge {badge}">{"all ECs pass" if result.passed else "not all pass"}'
              f"</span> at the nominal pose, {r.output.width} × {r.output.height} px"
              f"{' (first vehicle; all vehicles below)' if r.members else ''}</p>"
              + yield_note(r.run_dir, r.top[0].params, result.passed,
                           robust=bool(r.robust_rows))
              + signoff_note(r.run_dir, report_dir) + provenance_line(provenance())
              + "<nav><p>" + " · ".join(
                  f'<a href="#{s}">{escape(s.replace("-", " "))}</a>' for s in sections)
              + "</p></nav>")
    if r.scene_changed:
        header += ('<p class="warn"><b>The scene file changed after this run.</b> The images and '
                   "EC values below are recomputed with the scene as it is now, so they can "
                   "differ from the scores the run stored.</p>")
    if markets:
        header += markets_html(markets, run_dir)
    if r.members:
        header += members_section(r.members, r.top[0].params, r.output, r.criteria,
                                  r.settings.kind.aggregate or "min")
    if r.robust_rows:
        header += robust_section(r.top, r.robust_rows, r.settings)
    step("pictures, guidelines and tables")
    guides = guideline_figures(r.scene, r.top[0].params, r.output, r.images,
                               shown=(r.output, color))
    body = (header + _scene_section(r) + _images_section(r, color, annotated)
            + _ec_section(result) + guidelines_html(guides, table_name)
            + _params_section(r) + _convergence_section(r))
    step(f"the top-{len(r.top)} gallery")
    body += _gallery_section(r, str(run_dir), color)
    step("writing")
    summary = _Summary(title, result.score, result.passed, _group_status(result),
                       shrink(color, INDEX_THUMB_PX),
                       {} if guides.reason is not None else {table_name: guides.table})
    return page(f"RVM tuning review: {title}", body), summary


def _write(path: Path, text: str, staged: StagedFiles | None = None,
           files: dict[str, bytes] | None = None) -> None:
    """Write ``text`` to ``path`` and ``files`` (by name) beside it, whole: under temporary
    names, renamed into place at once, or by ``staged``'s commit when given (several
    pages, all or none; a page that fails drops its files from ``staged``)."""
    items: list[tuple[Path, str | bytes]] = [(path, text)]
    items += [(path.with_name(name), data) for name, data in (files or {}).items()]

    def put(into: StagedFiles) -> None:
        target = path
        try:
            for target, data in items:
                where = into.path(target)
                if isinstance(data, str):
                    write_text(where, data)
                else:
                    where.write_bytes(data)
        except OSError as err:
            for done, _ in items:
                into.drop(done)
            raise RvmsimError(f"{target}: {write_problem(err, 'cannot write report')}"
                              ) from None

    if staged is not None:
        put(staged)
        return
    with StagedFiles() as one:
        put(one)


# ---------------------------------------------------------------------------- public API
def write_report(run_dir: str | Path, out: str | Path | None = None, *,
                 progress: bool = False) -> Path:
    """Write the review report of one tuning run.

    Parameters
    ----------
    run_dir : path
        A run folder written by :func:`rvmsim.tune.tune` (``run.json``, ``run.sqlite``).
    out : path, optional
        The HTML file to write (default: ``run_dir/report.html``).  The guidelines' ECU
        table goes beside it (:func:`~rvmsim.report.guidelines.guideline_table_name`:
        ``guidelines.bin`` beside a ``report.html``), written with the page or not at all.
    progress : bool
        Show a progress bar over the report's steps on stderr.

    Returns
    -------
    Path
        The page written.

    Raises
    ------
    RvmsimError
        One line: not a run folder, no candidates yet, scene or criteria file gone,
        unwritable output.
    """
    run_dir = Path(run_dir)
    path = Path(out) if out is not None else run_dir / "report.html"
    with progress_bar(total=_STEPS, desc="report", unit="step", leave=False,
                      disable=not progress) as bar:
        text, summary = _build(run_dir, path.parent, bar, guideline_table_name(path))
        _write(path, text, files=summary.files)
    return path
