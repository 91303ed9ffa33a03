"""Run kinds as objects: what a tuning run searches over, how it writes its results, and what
it judges.

A run's settings name one kind (:func:`member_set`), and :func:`rvmsim.tune.tune` takes one
path through it for every kind:

- :class:`Single`: one scene, searched on its own image;
- :class:`Shared`: one parameter set for several scenes (a member per scene);
- :class:`Robust`: a single or shared run judged over mount and load variations (a member
  per scene's nominal image and per sample); with a compensation model it is
  :class:`Compensated`, judged after the end-of-line per-car values;
- :class:`Markets`: one parameter set for every (scene, market) pair, each with its
  market's criteria at its market's site.

Each kind builds its members and renders (:meth:`MemberSet.build`), searches them
(:meth:`MemberSet.search`, through :func:`rvmsim.tune.search_members` and
:func:`rvmsim.pipeline.make_evaluator`), writes its own result rows under ``best/`` and gives
its :class:`Verdict` (:meth:`MemberSet.write_results`).  The verdict is what ``rvmsim tune``'s
exit status comes from; nothing is read back from disk for it.

"Binding EC" has one meaning everywhere: the enabled EC with the lowest score under the
setting judged (:func:`rvmsim.criteria.binding_row`).  The EC that fails most often over a
robust run's samples is its *limiting* EC.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from ..render import cached_render
from ..runs.records import RunSettings
from ..runs.store import RunStore
from ..scene import Scene
from .loop import SearchOutcome, search_members, search_scene
from .markets import market_problem_lines, market_table_lines, markets_members, write_market_results
from .members import Member
from .requests import SearchOptions, SearchSettings
from .robust import robust_line, robust_members, run_compensation, write_robust_results
from .shared import scene_members, shared_problems, write_member_results
from .results import write_results

if TYPE_CHECKING:
    from ..compensation import CompensationModel
    from ..criteria import Criteria
    from ..markets import MarketMember
    from ..render import FisheyeImages
    from ..search.config import TuningConfig
    from ..search.strategies import Strategy

__all__ = ["Verdict", "Built", "MemberSet", "Single", "Shared", "Robust", "Compensated",
           "Markets", "member_set"]


@dataclass(frozen=True)
class Verdict:
    """What a run's best setting is judged to be.

    Attributes
    ----------
    passed : bool
        Whether the best setting passes everything the run judges (every EC of every
        member: every scene, every market); False also when the run has no trials.
    gate : bool
        Whether the run's exit status follows ``passed`` (shared and markets runs, which
        exist to find one setting that passes everywhere); a single or robust run reports
        its best setting and exits 0 (``rvmsim evaluate`` judges a setting).
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
    gate: bool = False
    problems: tuple[str, ...] = ()
    lines: tuple[str, ...] = ()
    shown: tuple[int, float] | None = None

    @property
    def exit_status(self) -> int:
        """``rvmsim tune``'s exit status: 1 when a gating run's best setting fails, else 0."""
        return 1 if self.gate and not self.passed else 0


@dataclass(frozen=True)
class Built:
    """A run's members made ready to search: the fisheye renders, the search members (None:
    one scene searched on its own image) and, for a markets run, the (scene, market) pairs
    (in the members' order)."""

    renders: list[FisheyeImages]
    members: list[Member] | None = None
    pairs: list[MarketMember] = field(default_factory=list)


class MemberSet(Protocol):
    """A run kind (see the module docstring)."""

    @property
    def name(self) -> str:
        """The kind's name, as messages call it (``single``, ``shared``, ``robust``, …)."""
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


@dataclass(frozen=True)
class Single:
    """One scene, searched on its own image."""

    settings: RunSettings
    name: str = "single"

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        return Built([cached_render(s, progress=progress)[0] for s in scenes])

    def search_settings(self, config: TuningConfig, criteria: Criteria,
                        strategy: Strategy) -> SearchSettings:
        return SearchSettings(config, criteria, strategy,
                              aggregate=self.settings.aggregate or "min")

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


@dataclass(frozen=True)
class Shared(Single):
    """One parameter set for several scenes: a member per scene; passes where every scene
    passes."""

    name: str = "shared"

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        renders = super().build(scenes, progress=progress).renders
        return Built(renders, scene_members(scenes, renders))

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        first = super().write_results(run_dir, store, scenes, built, criteria)
        written = write_member_results(run_dir, store, scenes, built.renders,
                                       self.settings.config, criteria,
                                       self.settings.aggregate or "min")
        if written is None:
            return Verdict(False, gate=True, problems=first.problems)
        doc, table = written
        problems = shared_problems(doc)
        lines = (table.rstrip(),) + (("", "no setting found passes every scene:",
                                      *(f"  {p}" for p in problems)) if problems else ())
        return Verdict(not problems, gate=True, problems=tuple(problems), lines=lines)


@dataclass(frozen=True)
class Robust:
    """A single or shared run (``inner``) judged over the variation's samples: per scene its
    nominal image, then its samples'.  Its verdict is ``inner``'s; the yield over the
    samples is reported with it (``best/robust.json``)."""

    settings: RunSettings
    inner: Single
    name: str = "robust"

    @property
    def compensation(self) -> CompensationModel | None:
        """The compensation model the run tunes for (None: the yield before it)."""
        return None

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        renders = [cached_render(s, progress=progress)[0] for s in scenes]
        return Built(renders, robust_members(scenes, renders, self.settings, progress=progress))

    def search_settings(self, config: TuningConfig, criteria: Criteria,
                        strategy: Strategy) -> SearchSettings:
        return SearchSettings(config, criteria, strategy,
                              aggregate=self.settings.aggregate or "min",
                              compensation=self.compensation)

    def search(self, built: Built, settings: SearchSettings, store: RunStore,
               options: SearchOptions) -> SearchOutcome:
        assert built.members is not None  # build() made them
        return search_members(built.members, settings, store, options=options)

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        inner = self.inner.write_results(run_dir, store, scenes,
                                         Built(built.renders), criteria)
        doc = write_robust_results(run_dir, store, self.settings, len(scenes))
        top = (doc or {}).get("top") or []
        shown = (int(top[0]["trial"]), float(top[0]["robust_score"])) if top else None
        return Verdict(inner.passed, inner.gate, inner.problems,
                       (*robust_line(doc), *inner.lines), shown)


@dataclass(frozen=True)
class Compensated(Robust):
    """A robust run judged after end-of-line compensation: each sample's picture with the
    per-car values the station writes for it (the run's compensation model)."""

    name: str = "compensated"

    @property
    def compensation(self) -> CompensationModel | None:
        return run_compensation(self.settings)


@dataclass(frozen=True)
class Markets:
    """One parameter set for every (scene, market) pair: each scene at the market's site,
    judged by the market's criteria; passes where every pair passes."""

    settings: RunSettings
    name: str = "markets"

    def build(self, scenes: Sequence[Scene], *, progress: bool = False) -> Built:
        pairs, renders, members = markets_members(scenes, self.settings, progress=progress)
        return Built(renders, members, pairs)

    def search_settings(self, config: TuningConfig, criteria: Criteria,
                        strategy: Strategy) -> SearchSettings:
        return SearchSettings(config, criteria, strategy,
                              aggregate=self.settings.aggregate or "min")

    def search(self, built: Built, settings: SearchSettings, store: RunStore,
               options: SearchOptions) -> SearchOutcome:
        assert built.members is not None  # build() made them
        return search_members(built.members, settings, store, options=options)

    def write_results(self, run_dir: Path, store: RunStore, scenes: Sequence[Scene],
                      built: Built, criteria: Criteria) -> Verdict:
        write_results(run_dir, store, built.pairs[0].scene, built.renders[0],
                      self.settings.config, criteria)
        written = write_market_results(run_dir, store, built.pairs, built.renders,
                                       self.settings.config)
        if written is None:
            return Verdict(False, gate=True, problems=("no trials",))
        doc, table = written
        problems = market_problem_lines(doc)
        return Verdict(bool(doc["passed"]), gate=True, problems=tuple(problems),
                       lines=(table.rstrip(), "", *market_table_lines(doc)))


def member_set(settings: RunSettings) -> MemberSet:
    """The run kind ``settings`` describe: markets, or a single or shared run, made robust
    (and compensated) when the settings say so."""
    if settings.markets:
        return Markets(settings)
    base = Shared(settings) if settings.shared else Single(settings)
    if not settings.robust:
        return base
    if settings.compensation is not None:
        return Compensated(settings, base)
    return Robust(settings, base)
