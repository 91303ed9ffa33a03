"""One setting for several markets (``rvmsim tune SCENE --markets fmvss111-full,unr158``).

Each (scene, market) pair is a member of the run (:mod:`rvmsim.tune.members`): the scene at
the market's test site (:func:`rvmsim.markets.market_scene`, rendered once and cached),
judged with the market's criteria.  A candidate passes when it passes every member; its EC
score is the members' minimum (``--aggregate``).  The run records its markets
(:attr:`rvmsim.runs.RunSettings.markets`), so ``--resume`` rebuilds the same members.

At the end, ``best/markets.json`` has one row per member (market): its EC score under the
best setting, pass or fail, the *binding* criterion (the EC with the least score: the one
that limits the setting in that market) and, where it fails, the failing ECs.  When no
setting passes every market the file also says why (:func:`market_verdict`):

- ECs no setting can pass in a market, read from the fisheye labels (the ECs' feasibility
  reasons, :func:`rvmsim.batch.infeasible_ecs`: e.g. a far cylinder hidden behind the
  bumper in the fisheye image itself);
- conflicts: markets that each pass alone in some trial but never together, with the ECs
  of the other market that fail in the trials where one passes (the conflicting ECs).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any, Sequence

from .._io import read_json_file, validate_document
from ..errors import ResultFileError, RvmsimError
from .markets_file import MarketsFile
from .members import Member, check_cameras, member_conflicts, member_passes
from ..markets import binding_row, market_members, parse_markets
from ..render import cached_render
from ..criteria.infeasible import infeasible_ecs
from ..pipeline import evaluate_params, record_output, write_frame
from ..runs.folder import open_run, run_settings
from .shared import resumed_scenes
from ..scene import load_scene

if TYPE_CHECKING:
    from ..criteria.infeasible import Infeasibility
    from ..markets import MarketMember
    from ..render import FisheyeImages
    from ..runs.records import RunSettings
    from ..runs.store import RunStore
    from ..scene import Scene
    from ..search.config import TuningConfig

__all__ = ["markets_members", "render_market_members",
           "market_infeasible", "write_market_results",
           "judge_run_in_markets",
           "market_verdict", "market_summary_lines", "market_table_lines", "load_markets", "market_problem_lines", "MARKETS_JSON"]

#: The per-market results of a markets run, in its ``best/`` folder.
MARKETS_JSON = "markets.json"


def markets_members(scenes: Sequence[Scene], settings: RunSettings, *, progress: bool = False
                    ) -> tuple[list[MarketMember], list[FisheyeImages], list[Member]]:
    """The members of a markets run: every (scene, market) pair, each scene rendered at the
    market's site (cached), with the market's criteria."""

    pairs = market_members(scenes, parse_markets(list(settings.kind.markets)))
    renders, members = render_market_members(pairs, progress=progress)
    return pairs, renders, members


def render_market_members(pairs: Sequence[MarketMember], *, progress: bool = False
                          ) -> tuple[list[FisheyeImages], list[Member]]:
    """Each (scene, market) pair's site scene rendered (cached) and made a search member
    with the market's criteria; the pairs' cameras checked to share one sensor size.

    Raises
    ------
    RvmsimError
        One line naming the pair whose camera differs.
    """

    renders = [cached_render(p.scene, progress=progress)[0] for p in pairs]
    check_cameras([(p.name, im.camera) for p, im in zip(pairs, renders)])
    members = [Member(p.name, im.labels, im.camera, p.scene, None, p.criteria)
               for p, im in zip(pairs, renders)]
    return renders, members


def market_infeasible(pairs: Sequence[MarketMember], renders: Sequence[FisheyeImages]
                      ) -> list[tuple[MarketMember, Infeasibility]]:
    """Per pair, the ECs no ISP setting can pass at its market's site, read from its fisheye
    labels (:func:`rvmsim.criteria.infeasible.infeasible_ecs`), in the pairs' order."""

    return [(p, f) for p, im in zip(pairs, renders)
            for f in infeasible_ecs(p.scene, im.camera, im.labels, p.criteria)]


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "member"


def write_market_results(run_dir: Path, store: RunStore, pairs: Sequence[MarketMember],
                         renders: Sequence[FisheyeImages], config: TuningConfig, *,
                         searched: bool = True) -> tuple[dict[str, Any], str] | None:
    """``best/markets/<member>/`` (each member's RVM image and annotated ECs under the best
    setting, at the RVM image of record), ``best/markets.json`` (see the module docstring)
    and, for a run that searched these markets (``searched``), ``best/members.json`` and
    ``best/ec_table.txt``.  A run tuned otherwise and judged in markets afterwards
    (:func:`judge_run_in_markets`) gets no conflicts (it has no member results) and keeps
    its own EC table.  Returns the ``markets.json`` document and the EC table (empty when
    not ``searched``); None without trials."""

    top = store.top(1)
    if not top:
        return None
    best = top[0]
    best_dir = run_dir / "best"
    rows, docs, tables, scores = [], [], [], []
    for p, im in zip(pairs, renders):
        record = record_output(p.criteria, p.scene, config.output.mirror)
        frame = evaluate_params(im, best.params, record, p.criteria)
        write_frame(frame, best_dir / "markets" / _slug(p.name))
        ec = frame.ec
        scores.append(ec.score)
        failing = [v.id for v in ec.items if v.enabled and not v.passed]
        rows.append({"member": p.name, "market": p.market.name, "title": p.market.title,
                     "vehicle": p.scene.name, "site": p.scene.test_site.site,
                     "ec_score": ec.score, "passed": not failing, "failing": failing,
                     "binding": binding_row(ec.items),
                     "images": f"markets/{_slug(p.name)}"})
        docs.append({"member": p.name, "market": p.market.name, "vehicle": p.scene.name,
                     **ec.as_dict()})
        tables.append(f"{p.name} ({p.market.title or p.market.name}):\n{ec.table()}")
    passed = all(r["passed"] for r in rows)
    verdict = market_verdict(store, pairs, renders, passed, conflicts=searched)
    rec = record_output(pairs[0].criteria, pairs[0].scene)
    doc = {"trial": best.idx, "ec_score": best.score if searched else min(scores),
           "passed": passed, "judged_at": [rec.width, rec.height], "searched": searched,
           "markets": rows, **verdict}
    (best_dir / MARKETS_JSON).write_text(json.dumps(doc, indent=2))
    if not searched:
        return doc, ""
    (best_dir / "members.json").write_text(json.dumps(
        {"trial": best.idx, "ec_score": best.score, "passed": best.passed, "members": docs},
        indent=2))
    head = (f"one setting for {len(pairs)} markets, EC score {best.score:.4g}, "
            f"{'all pass' if best.passed else 'fails ' + ','.join(best.failing())}")
    table = head + "\n\n" + "\n\n".join(tables) + "\n"
    (best_dir / "ec_table.txt").write_text(table)
    return doc, table


def market_verdict(store: RunStore, pairs: Sequence[MarketMember],
                   renders: Sequence[FisheyeImages], passed: bool, *,
                   conflicts: bool = True) -> dict[str, Any]:
    """Why no setting passes every market (empty when the best one does): ``infeasible``
    (per member, the ECs no setting can pass there, from the fisheye labels) and
    ``conflicts`` (pairs of members that each pass alone in some trial but never
    together, with the ECs of the other that fail in the trials where one passes, most
    often first)."""
    if passed:
        return {}
    infeasible = [{"member": p.name, "ec": f.ec, "reason": f.reason}
                  for p, f in market_infeasible(pairs, renders)]
    if not conflicts:  # judged after a search of other criteria: no member results
        return {"infeasible": infeasible, "conflicts": []}
    per = member_passes(store, len(pairs))
    return {"infeasible": infeasible,
            "conflicts": member_conflicts(store, [p.name for p in pairs], per),
            "passes_alone": {p.name: len(per[k]) for k, p in enumerate(pairs)}}


def market_summary_lines(run_dir: Path) -> list[str]:
    """The per-market table ``rvmsim tune`` prints (none for other runs)."""
    doc = load_markets(run_dir)
    return [] if doc is None else market_table_lines(doc)


def market_table_lines(doc: dict[str, Any]) -> list[str]:
    """:func:`market_summary_lines` from a ``markets.json`` document (what
    :func:`write_market_results` returns)."""
    lines = [f"{'market':<24} {'EC score':>8}  {'result':<6}  binding criterion"]
    for r in doc["markets"]:
        b = r.get("binding") or {}
        value = "—" if b.get("value") is None else f"{b['value']:.4g}{b.get('unit', '')}"
        lines.append(f"{r['member']:<24} {r['ec_score']:>8.4g}  "
                     f"{'pass' if r['passed'] else 'FAIL':<6}  {b.get('ec', '—')} "
                     f"{b.get('name', '')} = {value}"
                     + ("" if r["passed"] else f"; fails {', '.join(r['failing'])}"))
    problems = market_problem_lines(doc)
    if problems:
        lines.append("no setting found passes every market:")
        lines += [f"  {p}" for p in problems]
    return lines


def market_problem_lines(doc: dict[str, Any]) -> list[str]:
    """Why no setting passes every market, one line per reason, from a ``markets.json``
    document (none when its best setting passes every market): the ECs no setting can pass
    in a market, the pairs of markets that pass alone but never together with their
    conflicting ECs, else the markets no trial passed."""
    if doc.get("passed"):
        return []
    lines = [f"{f['member']}: {f['reason']} (no setting can pass it)"
             for f in doc.get("infeasible", [])]
    for c in doc.get("conflicts", []):
        a, b = c["members"]
        sides = []
        for passes, fails in ((a, b), (b, a)):
            ecs = [e for e in c["ecs"] if e.get("member", b if passes == a else a) == fails]
            if ecs:
                sides.append(f"where {passes} passes, {fails} fails " + ", ".join(
                    f"{e['ec']} ({e['fails_in']} of {e['of']} trials)" for e in ecs))
        lines.append(f"{a} and {b} each pass alone but never together (conflicting ECs): "
                     + "; ".join(sides))
    if doc.get("searched") is False:  # judged after a search of other criteria
        lost = [f"{r['member']} (fails {', '.join(r.get('failing') or [])})"
                for r in doc["markets"] if not r["passed"]]
        lines.append(f"{'; '.join(lost)}: the run was tuned without these markets; tune with "
                     "--markets to search for a setting that passes every market")
    elif not doc.get("infeasible") and not doc.get("conflicts"):
        lost = [r["member"] for r in doc["markets"] if not r["passed"]]
        lines.append(f"{', '.join(lost)}: no trial passed (a larger --budget may; no EC is "
                     "proven impossible from the fisheye labels)")
    return lines


def judge_run_in_markets(run_dir: str | Path, markets: str) -> dict[str, Any]:
    """Judge the best setting of a finished run in ``markets`` (``report`` and ``signoff``
    with ``--markets``): each scene of the run at each market's site, with the market's
    criteria, written as a markets run writes them (``best/markets.json``,
    ``best/markets/<member>/``); the run's own results stay as they are.  A run tuned for
    markets keeps its rows: give no ``--markets``, or its own.  Returns the ``markets.json``
    document (:func:`market_table_lines` prints it).

    Raises
    ------
    RvmsimError
        One line: no run there, bad markets, or a markets run given other markets.
    """

    run_dir = Path(run_dir)
    chosen = parse_markets(markets)
    store = open_run(run_dir)
    try:
        settings = run_settings(run_dir, store)
        if settings.kind.markets:
            if tuple(m.spec for m in chosen) != settings.kind.markets:
                raise RvmsimError(f"{run_dir}: this run was tuned for the markets "
                                  f"{', '.join(settings.kind.markets)}; give no --markets (its rows "
                                  "are shown) or the same markets")
            doc = load_markets(run_dir)
            if doc is None:
                raise RvmsimError(f"{run_dir / 'best' / MARKETS_JSON}: missing; resume the run "
                                  "to write its market verdicts")
            return doc

        scenes = resumed_scenes(settings) if settings.shared else [load_scene(settings.scene)]
        pairs = market_members(scenes, chosen)
        renders = [cached_render(p.scene)[0] for p in pairs]
        written = write_market_results(run_dir, store, pairs, renders, settings.config,
                                       searched=False)
    finally:
        store.close()
    if written is None:
        raise RvmsimError(f"{run_dir}: the run has no trials to judge")
    return written[0]


def load_markets(run_dir: str | Path) -> dict[str, Any] | None:
    """The run's ``best/markets.json`` (None: not a markets run).

    Raises
    ------
    RvmsimError
        One line naming the file: over the JSON limits, not JSON, or not of its schema
        (:class:`~rvmsim.tune.markets_file.MarketsFile`: the key at fault).
    """

    path = Path(run_dir) / "best" / MARKETS_JSON
    if not path.is_file():
        return None
    doc: dict[str, Any] = validate_document(MarketsFile, read_json_file(
        path, ResultFileError, what="markets file"), str(path), ResultFileError)
    return doc
