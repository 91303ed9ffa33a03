"""Sweeps over markets: every design point tuned to pass several markets at once.

Sweep file::
    tune:
      markets: [fmvss111-full, unr158]   # instead of tune.criteria (not both)

Each market (:mod:`rvmsim.markets`: a test site and the criteria judged there) makes the
point's scene at its site a *member* of the point's search, as ``rvmsim tune --markets``
does (:func:`rvmsim.tune.search_members`): each market's site scene is rendered once per
point (through the worker's render cache), a candidate's EC score is the markets' minimum,
and it passes only when it passes every market.  A point is ``infeasible`` when some market
has an EC no setting can pass there (:func:`~rvmsim.batch.feasibility.infeasible_ecs` on
that market's site render with its criteria); the reason names the market.

Results (:func:`run_markets_point`) carry, besides the keys of a one-criteria point,
``markets`` (per market: its EC score under the point's best setting, passed, its failing
ECs and its binding EC) and ``limiting_market`` (the market of ``limiting_ec``: the failing
EC with the lowest score over all markets).

The yield of a markets point (:func:`markets_yield`) counts a variation sample as passing
only when it passes every market: each market's site is rendered at the sample's mount and
load, the same Sobol samples in every market.

Markets given as ``SITE:CRITERIA`` files are read on the worker at their absolute paths (as
mesh files are): on a cluster they must be readable there too.
"""

from __future__ import annotations

import functools
import hashlib
import json
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from .._io import KeyPath
from ..criteria import bundled_criteria_text, record_size
from ..errors import InputFileError, RvmsimError
from ..isp import IspParams
from ..markets import market_criteria, market_members, parse_markets
from ..robust import RobustnessSettings, markets_robustness
from ..runs import RunStore
from ..scene import bundled_site, scene_from_dict
from ..tune import MembersScorer, SearchSettings, member_evaluators, search_members
from ..search import TuningConfig, make_strategy
from ..tune.markets import market_infeasible, render_market_members
from .axes import sweep_error
from .payloads import InfeasibleDoc, MarketOutcomeDoc, PointResult, PointRun, PointTask
from .probes import RENDER_LOCK, probe_sensitivity, task_budget

if TYPE_CHECKING:
    from ..isp import OutputSpec
    from ..markets import Market, MarketMember
    from ..render import FisheyeImages
    from ..tune import Member
    from .payloads import YieldDoc, YieldError

__all__ = ["sweep_markets", "markets_fingerprint", "market_ec_ids", "market_names",
           "run_markets_point", "markets_yield", "market_outcomes"]


# ---------------------------------------------------------------------------- the file
def sweep_markets(entries: Sequence[str] | None, criteria_given: bool, source: str,
                  lines: Mapping[KeyPath, int], folder: Path) -> tuple[str, ...]:
    """The specs (:attr:`rvmsim.markets.Market.spec`) of a sweep file's ``tune.markets``,
    checked (each site and criteria loads); ``()`` when it has none.  ``SITE:CRITERIA``
    files are relative to ``folder`` (the sweep file's).

    Raises
    ------
    SweepFileError
        One line naming the sweep file and ``tune.markets``: given with ``tune.criteria``,
        empty, an unknown market, a repeat, a missing file.  A site or criteria file's own
        errors name that file.
    """

    if entries is None:
        return ()
    if criteria_given:
        raise sweep_error(source, lines, "tune.markets", "give tune.criteria or tune.markets, "
                          "not both (each market is judged by its own criteria)")
    if not entries:
        raise sweep_error(source, lines, "tune.markets", "give at least one market (e.g. "
                          "[fmvss111-full, unr158])")
    try:
        markets = parse_markets(list(entries), folder)
    except InputFileError:
        raise
    except RvmsimError as err:  # parse_markets words it for the command line
        message = str(err).removeprefix("--markets").lstrip(": ")
        raise sweep_error(source, lines, "tune.markets", message) from None
    return tuple(m.spec for m in markets)


def _parsed(specs: Sequence[str]) -> tuple[Market, ...]:
    return parse_markets(list(specs))


def _text_of(name_or_file: str | None, bundled: str) -> str:
    """A market part's content for the fingerprint: a file's text, else the bundled name's
    definition (``bundled``)."""
    if name_or_file is not None and name_or_file.lower().endswith((".yaml", ".yml")):
        return Path(name_or_file).read_text()
    return bundled


def markets_fingerprint(specs: Sequence[str]) -> list[str]:
    """Per market, a hash of its spec, its site's definition and its criteria's text: a
    stored sweep resumes only with the same markets as they were."""

    out = []
    for m in _parsed(specs):
        site = _text_of(m.site, "" if m.site.lower().endswith((".yaml", ".yml"))
                        else repr(bundled_site(m.site)))
        crit = _text_of(m.criteria, (bundled_criteria_text(m.criteria) or m.criteria or "")
                        if m.criteria else "-")
        out.append(hashlib.sha256("\0".join([m.spec, site, crit]).encode()).hexdigest()[:20])
    return out


@functools.lru_cache(maxsize=32)
def _ec_ids(specs: tuple[str, ...]) -> tuple[str, ...]:
    ids = [ec for m in _parsed(specs) for ec in market_criteria(m).ids]
    return tuple(dict.fromkeys(ids))


def market_ec_ids(specs: Sequence[str]) -> tuple[str, ...]:
    """Every market's EC ids, in the markets' order, each once (the results' EC
    columns)."""
    return _ec_ids(tuple(specs))


def market_names(specs: Sequence[str]) -> tuple[str, ...]:
    """The markets' names (``fmvss111-full``; a ``SITE:CRITERIA`` market is named so)."""
    return tuple(m.name for m in _parsed(specs))


# ---------------------------------------------------------------------------- the task
def _members(task: PointTask
             ) -> tuple[list[MarketMember], list[FisheyeImages], list[Member]]:
    """The point's scene at every market's site, each rendered (cached, same sensor) and
    made a search member (:func:`rvmsim.tune.markets.render_market_members`)."""

    scene = scene_from_dict(task["scene"], source=task["label"])
    pairs = market_members([scene], _parsed(task.get("markets", ())))
    with RENDER_LOCK:  # one OpenGL context at a time per process
        renders, members = render_market_members(pairs)
    return pairs, renders, members


def _infeasible(pairs: Sequence[MarketMember], renders: Sequence[FisheyeImages]
                ) -> list[InfeasibleDoc]:
    """Per market, the ECs no setting can pass at its site, the reason naming the market
    (:func:`rvmsim.tune.markets.market_infeasible`)."""

    return [{"ec": f.ec, "market": p.market.name, "reason": f"{p.market.name}: {f.reason}",
             "short": f"{p.market.name} {f.short}"} for p, f in market_infeasible(pairs, renders)]


def market_outcomes(store: RunStore, idx: int, pairs: Sequence[MarketMember]
                    ) -> dict[str, MarketOutcomeDoc]:
    """Per market (by name, in order), its own verdict on trial ``idx`` of a markets
    search (the store's ``members`` table): EC score, passed, the failing enabled ECs and
    the binding EC (the enabled EC with the least score)."""

    rows = {int(k): (float(s), bool(ok), json.loads(ec)) for k, s, ok, ec in store.rows(
        "SELECT member, score, passed, ec FROM members WHERE idx = ?", (idx,))}
    out: dict[str, MarketOutcomeDoc] = {}
    for k, p in enumerate(pairs):
        score, ok, ecs = rows[k]
        enabled = {e: c for e, c in ecs.items() if p.criteria.items[e].enabled}
        out[p.market.name] = {
            "score": score, "passed": ok,
            "failing": [e for e, c in enabled.items() if not c[2]],
            "binding": min(enabled, key=lambda e: enabled[e][1]) if enabled else None,
            "ecs": {e: {"value": c[0], "score": c[1], "passed": bool(c[2])}
                    for e, c in ecs.items()}}
    return out


def _limiting(outcomes: Mapping[str, MarketOutcomeDoc]) -> tuple[str | None, str | None]:
    """(EC, market) of the failing enabled EC with the lowest score over every market
    (the first market among equals); (None, None) when every market passes."""
    failing = [(o["ecs"][e]["score"], k, e, name)
               for k, (name, o) in enumerate(outcomes.items()) for e in o["failing"]]
    if not failing:
        return None, None
    _, _, ec, market = min(failing)
    return ec, market


def run_markets_point(task: PointTask) -> PointResult:
    """:func:`~rvmsim.batch.point.run_point` for a markets sweep (``task["markets"]``): the
    point tuned for every market at once (see the module docstring).  The result is a
    :class:`~rvmsim.batch.payloads.PointRun` with ``markets`` and ``limiting_market``; a
    problem with the point is ``{"error", "seconds"}``."""
    t0 = time.perf_counter()
    try:
        pairs, renders, members = _members(task)
        rendered = time.perf_counter() - t0
        result = _search(task, pairs, renders, members)
    except RvmsimError as err:
        return {"error": str(err), "seconds": time.perf_counter() - t0}
    result["phases"] = {"render": rendered, **result.get("phases", {})}
    result["seconds"] = time.perf_counter() - t0
    return result


def _search(task: PointTask, pairs: Sequence[MarketMember],
            renders: Sequence[FisheyeImages], members: Sequence[Member]) -> PointRun:
    """Tune, then judge and probe the best setting of one markets point.  A point some
    market makes infeasible is proven so before any search: one candidate fills its EC
    columns, and it gets neither a sensitivity probe nor a yield (as a one-criteria
    point, :func:`~rvmsim.batch.point.run_point`)."""

    config = TuningConfig.model_validate(task["config"]).at_record(
        record_size(pairs[0].criteria, pairs[0].scene))
    t = time.perf_counter()
    infeasible = _infeasible(pairs, renders)
    space = config.space(members[0].camera)
    budget = task_budget(task, renders[0], config)
    if infeasible:  # the verdict is proven: one candidate, every setting fails alike
        strat = make_strategy("random", space, config, task["seed"], 1)
    else:
        strat = make_strategy(task["strategy"], space, config, task["seed"], budget,
                              [space.vector(IspParams(**p)) for p in task.get("starts", ())])
    store = RunStore(":memory:")
    try:
        outcome = search_members(members, SearchSettings(config, pairs[0].criteria, strat),
                                 store)
        best = outcome.best
        if best is None:
            raise RvmsimError(f"{task['label']}: the search evaluated no candidate")
        outcomes = market_outcomes(store, best.idx, pairs)
        n_eval = store.count()
    finally:
        store.close()
    limiting, market = _limiting(outcomes)
    result: PointRun = {
        "score": best.score, "passed": bool(best.passed),
        "ecs": {ec: {"value": o.value, "score": o.score, "passed": o.passed}
                for ec, o in best.ecs.items()},
        "params": {n: getattr(best.params, n) for n in best.params.names()},
        "tuned": list(space.names), "evaluations": n_eval, "budget": budget,
        "stopped": "infeasible" if infeasible else outcome.stopped, "infeasible": infeasible,
        "limiting_ec": limiting, "limiting_market": market, "markets": outcomes}
    if task.get("sensitivity", True) and not infeasible:
        scorer = MembersScorer(member_evaluators(members, config.output_spec(),
                                                 pairs[0].criteria), space)
        result["sensitivity"] = probe_sensitivity(lambda xs: scorer(xs).score, space,
                                                  best.params)
    phases = {"tune": time.perf_counter() - t}
    t = time.perf_counter()
    rob, beat = task.get("robustness"), task.get("beat")
    if rob is None or rob["samples"] <= 0 or pairs[0].scene.variation is None:
        pass  # no yield asked for
    elif infeasible:
        result["robustness"] = {"error": "not measured: the point is infeasible ("
                                + "; ".join(x["reason"] for x in infeasible) + ")",
                                "seconds": 0.0}
    elif beat is None or (result["passed"], result["score"]) > tuple(beat):
        result["robustness"] = markets_yield(pairs, best.params, config.output_spec(),
                                             rob["samples"], rob["seed"])
    phases["yield"] = time.perf_counter() - t
    result["phases"] = phases
    return result


# ---------------------------------------------------------------------------- the yield
def markets_yield(pairs: Sequence[MarketMember], params: IspParams, output: OutputSpec,
                  samples: int, seed: int, render_scale: float = 1.0
                  ) -> YieldDoc | YieldError:
    """The yield of ``params`` over every market at once: the share of variation samples
    that pass every enabled EC of every market (each market's site rendered at the
    sample's mount and load; the same Sobol samples everywhere), as
    :func:`~rvmsim.batch.yields.point_yield` gives it; EC ids in ``limiting_ec`` and
    ``failure_rates`` are ``market: EC``.  ``{"error"}`` when it cannot be measured.

    Parameters
    ----------
    pairs : sequence of MarketMember
        The point's scene at each market's site, with the market's criteria.
    params : IspParams
        The point's best setting, for the full sensor.
    output : OutputSpec
        The RVM image the ECs are measured on.
    samples, seed : int
        Variation samples at tolerance scale 1 and their Sobol seed.
    render_scale : float
        Fraction of the sensor rendered (1, as the point's tuning renders it).
    """

    t0 = time.perf_counter()
    try:
        with RENDER_LOCK:  # every market on the same samples (rvmsim robustness --markets)
            res = markets_robustness(pairs[0].scene, params, pairs, RobustnessSettings(
                output, pairs[0].criteria, samples=samples, seed=seed, scales=(1.0,),
                render_scale=render_scale), frames=False)
    except RvmsimError as err:
        return {"error": f"yield: {err}", "seconds": time.perf_counter() - t0}
    est = res.estimate
    stats = [(f"{m.name}: {e.id}", e) for m in res.markets for e in m.result.ecs
             if e.enabled]
    failing = [(name, e) for name, e in stats if e.n_fail]
    top = max(failing, key=lambda t: t[1].failure_rate) if failing else None
    driver = top[1].driver if top is not None else None
    return {"yield": est.yield_, "ci95": [est.ci[0], est.ci[1]], "n_pass": est.n_pass,
            "n": est.n, "seed": seed,
            "limiting_ec": None if top is None else top[0],
            "limiting_fail_rate": None if top is None else top[1].failure_rate,
            "limiting_axis": None if driver is None else driver.axis,
            "limiting_driver": None if driver is None else driver.describe(),
            "failure_rates": {name: e.failure_rate for name, e in stats},
            "seconds": time.perf_counter() - t0}
