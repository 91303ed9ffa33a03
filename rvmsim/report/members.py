"""The members of a shared run in its report: a row per vehicle (scene) with its EC score,
each EC's pass/fail and a thumbnail of its RVM image under the chosen parameters, and each
top-M candidate's per-vehicle scores (section id ``members``).

The scores shown in the table are measured again on each scene as it is now (as the rest of
the report is); the gallery's per-vehicle scores are those the run stored.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

from ..errors import RvmsimError
from .page import escape, img_tag
from ..render import cached_render
from ..scene import load_scene
from ..pipeline import evaluate_params

if TYPE_CHECKING:
    from ..criteria import Criteria
    from ..isp import IspParams, OutputSpec
    from ..render import FisheyeImages
    from ..scene import Scene
    from ..runs import RunSettings, RunStore, TrialRecord
    from ..tune.robust import RobustSummary

__all__ = ["MemberScene", "load_member_scenes", "members_section", "member_scores_html",
           "MEMBER_THUMB_PX", "robust_section"]

#: Longest side of a member's thumbnail (px).
MEMBER_THUMB_PX = 240


@dataclass(frozen=True)
class MemberScene:
    """One scene of a shared run as the report shows it: its vehicle, the scene file it was
    found at, the scene and its rendered images."""

    vehicle: str
    scene_file: Path
    scene: Scene
    images: FisheyeImages


def load_member_scenes(settings: RunSettings, run_dir: Path,
                       resolve: Callable[[str, Path], Path | None]) -> list[MemberScene]:
    """The scenes of a shared run (empty for a one-scene run), rendered (cached).

    Raises
    ------
    RvmsimError
        One line: a scene file of the run not found.
    """

    out = []
    for ref in settings.scenes:
        path = resolve(ref.scene, run_dir)
        if path is None:
            raise RvmsimError(f"{run_dir}: scene file {ref.scene} not found")
        sc = load_scene(path)
        out.append(MemberScene(sc.name, path, sc, cached_render(sc)[0]))
    return out


def members_section(members: Sequence[MemberScene], params: IspParams, output: OutputSpec,
                    criteria: Criteria, aggregate: str) -> str:
    """The ``members`` section: a row per vehicle under ``params`` (rank 1)."""

    ids = [c for c in criteria.ids if criteria.items[c].enabled]
    head = ("<tr><th>vehicle</th><th>RVM image</th><th>EC score</th>"
            + "".join(f"<th>{escape(e)}</th>" for e in ids) + "</tr>")
    rows = []
    for m in members:
        frame = evaluate_params(m.images, params, output, criteria, annotate=False)
        items = {i.id: i for i in frame.ec.items}
        cells = "".join(
            f'<td class="{st}">{escape(st)}</td>'
            for st in ("pass" if items[e].passed else "fail" for e in ids))
        rows.append(
            f'<tr class="member"><td>{escape(m.vehicle)}<br><span class="muted">'
            f'{escape(m.scene_file)}</span></td>'
            f'<td>{img_tag(frame.color, m.vehicle + " RVM image", MEMBER_THUMB_PX)}</td>'
            f'<td class="num {"pass" if frame.ec.passed else "fail"}">{frame.ec.score:.4g}</td>'
            f"{cells}</tr>")
    return (f'<section id="members"><h2>Vehicles sharing this setting</h2>'
            f'<p class="muted">{len(members)} scenes tuned together; the run\'s EC score is '
            f'their {escape(aggregate)}, and a candidate passes where it passes on every '
            f'scene.</p><table>{head}{"".join(rows)}</table></section>')


def member_scores_html(members: Sequence[MemberScene], scores: Sequence[float]) -> str:
    """A gallery card's per-vehicle EC scores (empty without stored member results)."""
    if not scores:
        return ""
    items = "".join(f"<li>{escape(m.vehicle)}: {s:.4g}</li>" for m, s in zip(members, scores))
    return f'<ul class="member-scores">{items}</ul>'


def robust_section(top: Sequence[TrialRecord], rows: Sequence[RobustSummary | None],
                   settings: RunSettings) -> str:
    """The ``robust`` section: the top-M's nominal score, robust score (the worst member's,
    or the run's quantile) and yield over the variation samples, side by side."""
    body = []
    for rank, (rec, row) in enumerate(zip(top, rows), 1):
        if row is None:
            continue
        lo, hi = row["yield_ci"]
        body.append(
            f'<tr><td class="num">{rank}</td><td class="num">{rec.idx}</td>'
            f'<td class="num {"pass" if row["nominal_passed"] else "fail"}">'
            f'{row["nominal_score"]:.4g}</td>'
            f'<td class="num {"pass" if rec.passed else "fail"}">{rec.score:.4g}</td>'
            f'<td class="num">{100 * row["yield"]:.1f} % ({100 * lo:.0f}–{100 * hi:.0f} %)</td>'
            "</tr>")
    robust = settings.kind.robust
    assert robust is not None  # a robust run's section
    source = robust.variation_file or "the scene's variation section"
    return (f'<section id="robust"><h2>Robust tuning</h2><p class="muted">Each candidate was '
            f'judged on the nominal scene and {robust.samples} variation samples '
            f'(Sobol, seed {settings.seed}, from {escape(source)}); its robust score is their '
            f'{escape(settings.kind.aggregate or "min")}. The yield is the share of the samples '
            "where every EC passes, with its 95 % Wilson interval; <code>rvmsim robustness"
            "</code> measures it on many more samples.</p><table><tr><th>rank</th>"
            "<th>trial</th><th>nominal score</th><th>robust score</th><th>yield (95 %)</th>"
            f'</tr>{"".join(body)}</table></section>')
