"""Member sets: what a tuning run of each kind searches over, how it writes its results, and
what it judges.

A request names its kind with an object (:class:`~rvmsim.tune.Shared`,
:class:`~rvmsim.tune.Robust`, :class:`~rvmsim.tune.Markets`; none: one scene), which
:func:`rvmsim.tune.new_run_settings` checks against the scenes and records
(:class:`rvmsim.runs.RunKind`); :func:`member_set` makes the stored settings a member set,
through which :func:`rvmsim.tune.tune` takes one path for every kind:

- :class:`SingleSet`: one scene, searched on its own image;
- :class:`SharedSet`: one parameter set for several scenes (a member per scene);
- :class:`RobustSet`: a single or shared run judged over mount and load variations (a member
  per scene's nominal image and per sample); :class:`CompensatedSet` judges them after the
  end-of-line per-car values;
- :class:`MarketsSet`: one parameter set for every (scene, market) pair.

Each builds its members and renders, searches them (through :func:`rvmsim.tune.search_members`
and :func:`rvmsim.pipeline.make_evaluator`), writes its own rows under ``best/``, gives its
:class:`Verdict` (``rvmsim tune``'s exit status; nothing is read back from disk for it) and
tells the report what it says of each top candidate (:meth:`MemberSet.top_rows`).

"Binding EC" has one meaning everywhere: the enabled EC with the lowest score under the
setting judged (:func:`rvmsim.criteria.binding_row`).  The EC that fails most often over a
robust run's samples is its *limiting* EC.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from ..criteria import Criteria, Unsupported, load_criteria, supported_criteria
from ..errors import RvmsimError
from ..markets import market_criteria, market_members, parse_markets
from ..render import cached_render, same_scene
from ..runs.records import RunSettings, TrialRecord
from ..runs.store import RunStore
from ..scene import Scene, load_scene
from ..search.config import TuningConfig
from .loop import SearchOutcome, search_members, search_scene
from .markets import (market_problem_lines, market_table_lines,
                      markets_members, write_market_results)
from .members import Member, parse_aggregate
from .requests import SearchOptions, SearchSettings
from .robust import (RobustSummary, robust_line, robust_members, robust_summary,
                     run_compensation, run_variations, variation_key, write_robust_results)
from .shared import resumed_scenes, scene_members, shared_problems, write_member_results
from .results import write_results

if TYPE_CHECKING:
    from ..compensation import CompensationModel
    from ..markets import MarketMember
    from ..render import FisheyeImages
    from ..search.strategies import Strategy

__all__ = ["Verdict", "Built", "TopRows", "MemberSet", "SingleSet", "SharedSet", "RobustSet",
           "CompensatedSet", "MarketsSet", "member_set"]


@dataclass(frozen=True)
class Verdict:
    """What a run's best setting is judged to be.

    Attributes
    ----------
    passed : bool
        Whether the best setting passes everything the run judges (every EC of every
        member: every scene, every market); False also when the run has no trials.
    problems : tuple of str
        Why the best setting fails, one line per reason (empty when it passes).
    lines : tuple of str
        What ``rvmsim tune`` prints after its head line: the best setting's EC table, a
        robust run's yield, a markets run's table.
    shown : (int, float), optional
        The trial shown as the run's best and its score, when that is not the best EC
        score's (a robust run shows its rank 1 and its robust score).
    """

    passed: bool
    problems: tuple[str, ...] = ()
    lines: tuple[str, ...] = ()
    shown: tuple[int, float] | None = None

    @property
    def exit_status(self) -> int:
        """``rvmsim tune``'s exit status: 0 when the best setting passes everything the run
        judges, 1 when it fails (as every judging command: docs/errors.md)."""
        return 0 if self.passed else 1


@dataclass(frozen=True)
class Built:
    """A run's members made ready to search: the fisheye renders, the search members (None:
    one scene searched on its own image) and, for a markets run, the (scene, market) pairs
    (in the members' order)."""

    renders: list[FisheyeImages]
    members: list[Member] | None = None
    pairs: list[MarketMember] = field(default_factory=list)


@dataclass(frozen=True)
class TopRows:
    """What a run's kind says of each of its top candidates, read from its store (for the
    report): each one's EC score on every member (by trial index; a shared or markets run),
    and each one's nominal score, robust score and sample yield (a robust run; None where
    the store holds no member results)."""

    member_scores: dict[int, list[float]] = field(default_factory=dict)
    robust: list[RobustSummary | None] = field(default_factory=list)


class MemberSet(Protocol):
    """A run kind (see the module docstring)."""

    @property
    def name(self) -> str:
        """The kind's name, as messages call it (``single``, ``shared``, ``robust``, …)."""
        ...

    def resumed_scenes(self, db: Path) -> list[Scene]:
        """The scenes of the stored run (``db``: its store, for messages), each checked
        unchanged since the run started (a changed one refused with one line)."""
        ...

    def resumed_criteria(self) -> Criteria:
        """The criteria of the stored run (the same ECs left out again)."""
        ...

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        """Render the members (cached) and make them search members."""
        ...

    def search_settings(self, config: TuningConfig, criteria: Criteria,
                        strategy: Strategy) -> SearchSettings:
        """What the search is asked: config, criteria, strategy, the members' aggregate and
        the compensation model."""
        ...

    def search(self, built: Built, settings: SearchSettings, store: RunStore,
               options: SearchOptions) -> SearchOutcome:
        """Search the members into ``store``."""
        ...

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        """Write ``top/`` and ``best/`` and judge the best setting."""
        ...

    def top_rows(self, store: RunStore, top: Sequence[TrialRecord]) -> TopRows:
        """What the kind says of each of ``top`` (its stored member results)."""
        ...

    def shown(self, scene: Scene, criteria: Criteria) -> tuple[Scene, Criteria]:
        """The member that ``best/``, the report and the console show, from the run's first
        scene and the criteria it records, as the caller loaded them: they themselves,
        except for a markets run (the scene at its first market's site, that market's
        criteria)."""
        ...


@dataclass(frozen=True)
class SingleSet:
    """One scene, searched on its own image."""

    settings: RunSettings
    name: str = "single"

    def resumed_scenes(self, db: Path) -> list[Scene]:
        st = self.settings
        sc = load_scene(st.scene)
        if st.scene_key is not None and not same_scene(st.scene_key, sc, st.scene):
            raise RvmsimError(f"{st.scene}: the scene changed since this run started; "
                              "resuming would mix two scenes (start a new run)")
        return [sc]

    def resumed_criteria(self) -> Criteria:
        st = self.settings
        crit = load_criteria(st.criteria_file)
        if st.left_out:  # tuned with --only-supported: the same ECs left out again
            crit = supported_criteria(crit, [Unsupported(k, ()) for k in st.left_out
                                             if k in crit.items])
        return crit

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        return Built([cached_render(s, progress=progress)[0] for s in scenes])

    def search_settings(self, config: TuningConfig, criteria: Criteria,
                        strategy: Strategy) -> SearchSettings:
        return SearchSettings(config, criteria, strategy,
                              aggregate=self.settings.kind.aggregate or "min")

    def search(self, built: Built, settings: SearchSettings, store: RunStore,
               options: SearchOptions) -> SearchOutcome:
        if built.members is not None:
            return search_members(built.members, settings, store, options=options)
        return search_scene(built.renders[0], settings, store, options=options)

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        best = write_results(run_dir, store, scenes[0], built.renders[0],
                             self.settings.config, criteria)
        if best is None:
            return Verdict(False, problems=("no trials",))
        failing = [v.id for v in best.items if v.enabled and not v.passed]
        return Verdict(best.passed, lines=(best.table(),),
                       problems=tuple(f"EC {k} fails" for k in failing))

    def top_rows(self, store: RunStore, top: Sequence[TrialRecord]) -> TopRows:
        return TopRows()  # one scene, its own image: nothing beyond the trial's score

    def shown(self, scene: Scene, criteria: Criteria) -> tuple[Scene, Criteria]:
        return scene, criteria


@dataclass(frozen=True)
class SharedSet(SingleSet):
    """One parameter set for several scenes: a member per scene; passes where every scene
    passes."""

    name: str = "shared"

    def resumed_scenes(self, db: Path) -> list[Scene]:
        _check_stored_aggregate(self.settings, db)
        return resumed_scenes(self.settings)

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        renders = super().build(scenes, progress=progress).renders
        return Built(renders, scene_members(scenes, renders))

    def top_rows(self, store: RunStore, top: Sequence[TrialRecord]) -> TopRows:
        return TopRows(member_scores=_member_scores(store, top))

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        first = super().write_results(run_dir, store, scenes, built, criteria)
        written = write_member_results(run_dir, store, scenes, built.renders,
                                       self.settings.config, criteria,
                                       self.settings.kind.aggregate or "min")
        if written is None:
            return Verdict(False, problems=first.problems)
        doc, table = written
        problems = shared_problems(doc)
        lines = (table.rstrip(),) + (("", "no setting found passes every scene:",
                                      *(f"  {p}" for p in problems)) if problems else ())
        return Verdict(not problems, problems=tuple(problems), lines=lines)


@dataclass(frozen=True)
class RobustSet:
    """A single or shared run (``inner``) judged over the variation's samples: per scene its
    nominal image, then its samples'.  Its verdict is ``inner``'s; the yield over the
    samples is reported with it (``best/robust.json``)."""

    settings: RunSettings
    inner: SingleSet
    name: str = "robust"

    @property
    def compensation(self) -> CompensationModel | None:
        """The compensation model the run tunes for (None: the yield before it)."""
        return None

    def resumed_scenes(self, db: Path) -> list[Scene]:
        st = self.settings
        _check_stored_aggregate(st, db)
        scenes = self.inner.resumed_scenes(db)
        rec = st.kind.robust
        assert rec is not None  # member_set made it robust for them
        if variation_key(run_variations(scenes, rec.variation_file)) != rec.variation_key:
            raise RvmsimError(f"{rec.variation_file or st.scene}: the variation changed since "
                              "this run started; resuming would mix two sample sets (start a "
                              "new run)")
        return scenes

    def resumed_criteria(self) -> Criteria:
        return self.inner.resumed_criteria()

    def shown(self, scene: Scene, criteria: Criteria) -> tuple[Scene, Criteria]:
        return self.inner.shown(scene, criteria)

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        renders = [cached_render(s, progress=progress)[0] for s in scenes]
        return Built(renders, robust_members(scenes, renders, self.settings, progress=progress))

    def search_settings(self, config: TuningConfig, criteria: Criteria,
                        strategy: Strategy) -> SearchSettings:
        return SearchSettings(config, criteria, strategy,
                              aggregate=self.settings.kind.aggregate or "min",
                              compensation=self.compensation)

    search = SingleSet.search  # its members always (build() makes them)

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        inner = self.inner.write_results(run_dir, store, scenes,
                                         Built(built.renders), criteria)
        doc = write_robust_results(run_dir, store, self.settings, len(scenes))
        top = (doc or {}).get("top") or []
        shown = (int(top[0]["trial"]), float(top[0]["robust_score"])) if top else None
        return Verdict(inner.passed, inner.problems,
                       (*robust_line(doc), *inner.lines), shown)

    def top_rows(self, store: RunStore, top: Sequence[TrialRecord]) -> TopRows:
        st = self.settings
        assert st.kind.robust is not None  # member_set made it robust for them
        n_scenes = max(1, len(st.scenes))
        rows = self.inner.top_rows(store, top)
        return TopRows(rows.member_scores, [robust_summary(store, rec.idx, n_scenes,
                                                           st.kind.robust.samples)
                                            for rec in top])


@dataclass(frozen=True)
class CompensatedSet(RobustSet):
    """A robust run judged after end-of-line compensation: each sample's picture with the
    per-car values the station writes for it (the run's compensation model)."""

    name: str = "compensated"

    @property
    def compensation(self) -> CompensationModel | None:
        return run_compensation(self.settings)


@dataclass(frozen=True)
class MarketsSet:
    """One parameter set for every (scene, market) pair: each scene at the market's site,
    judged by the market's criteria; passes where every pair passes."""

    settings: RunSettings
    name: str = "markets"

    def resumed_scenes(self, db: Path) -> list[Scene]:
        _check_stored_aggregate(self.settings, db)
        return resumed_scenes(self.settings)

    def resumed_criteria(self) -> Criteria:
        return market_criteria(parse_markets(list(self.settings.kind.markets))[0])

    def shown(self, scene: Scene, criteria: Criteria) -> tuple[Scene, Criteria]:
        first = market_members([scene], parse_markets(list(self.settings.kind.markets))[:1])[0]
        return first.scene, first.criteria

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        pairs, renders, members = markets_members(scenes, self.settings, progress=progress)
        return Built(renders, members, pairs)

    # searched as a shared run is: one setting for every member
    search_settings = SingleSet.search_settings
    search = SingleSet.search

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        write_results(run_dir, store, built.pairs[0].scene, built.renders[0],
                      self.settings.config, criteria)
        written = write_market_results(run_dir, store, built.pairs, built.renders,
                                       self.settings.config)
        if written is None:
            return Verdict(False, problems=("no trials",))
        doc, table = written
        problems = market_problem_lines(doc)
        return Verdict(bool(doc["passed"]), problems=tuple(problems),
                       lines=(table.rstrip(), "", *market_table_lines(doc)))

    def top_rows(self, store: RunStore, top: Sequence[TrialRecord]) -> TopRows:
        return TopRows(member_scores=_member_scores(store, top))


def member_set(settings: RunSettings) -> MemberSet:
    """The run kind ``settings`` describe: markets, or a single or shared run, made robust
    (and compensated) when the settings say so."""
    if settings.kind.markets:
        return MarketsSet(settings)
    base = SharedSet(settings) if settings.shared else SingleSet(settings)
    robust = settings.kind.robust
    if robust is None:
        return base
    if robust.compensation is not None:
        return CompensatedSet(settings, base)
    return RobustSet(settings, base)


def _member_scores(store: RunStore, top: Sequence[TrialRecord]) -> dict[int, list[float]]:
    return {rec.idx: [m[0] for m in store.member_results(rec.idx)] for rec in top}  # by trial


def _check_stored_aggregate(settings: RunSettings, db: Path) -> None:
    """Refuse a stored multi-member run whose aggregate this version cannot read."""
    try:
        parse_aggregate(settings.kind.aggregate or "min")
    except RvmsimError:
        raise RvmsimError(f"{db}: aggregate: {settings.kind.aggregate!r} is not min or quantile Q "
                          "(written by another rvmsim version?)") from None
