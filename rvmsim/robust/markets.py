"""The yield of one ISP setting in every market a car is sold in (``rvmsim robustness
--markets fmvss111-full,unr158``).

Every variation sample (one car off the line) is judged at each market's test site with
that market's criteria: the scene at the site (:func:`rvmsim.markets.market_scene`: the
same car, the site's objects standing on the ground) goes through :func:`robustness` as a
one-market run, on the same samples (the same variation and seed), so each market's
evaluation is the batch one of a single market.  A car passes *all markets* when it passes
every one of them; the all-markets yield is the share of such samples, with its 95 %
Wilson interval, and can be no larger than any market's.  A market's *limiting* EC is the
enabled EC that fails most often there (ties: the one with the least worst margin); its
*binding* EC is, as everywhere, the one with the least score under a setting
(:func:`rvmsim.markets.binding_ec`).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..isp import IspParams, OutputSpec, params_to_dict
from ..render import TaskRunner
from ..scene import Scene
from .robustness import EcStats, RobustnessResult, RobustnessSettings, _by_load, robustness
from .samples import MountSample
from .stats import YieldEstimate, YieldVerdict, limiting_ec, yield_estimate
from .variation import Variation, variation_from_scene

if TYPE_CHECKING:
    from ..markets import MarketMember

__all__ = ["MarketYield", "MarketsRobustness", "markets_robustness"]


@dataclass(frozen=True)
class MarketYield:
    """One market's yield: its name and title, the site and criteria it is judged with (a
    bundled name or a file, as :class:`rvmsim.markets.Market` has them; criteria None:
    the paper's), and the one-market :class:`RobustnessResult` at that site."""

    name: str
    title: str
    site: str
    criteria: str | None
    result: RobustnessResult

    @property
    def limiting(self) -> EcStats | None:
        """The enabled EC that fails on most samples (ties: the least worst margin); None
        when no EC fails."""
        return limiting_ec(self.result.ecs)

    def as_dict(self) -> dict[str, Any]:
        """The market's row of robustness.json (``markets``)."""
        r, b = self.result, self.limiting
        return {"market": self.name, "title": self.title, "site": self.site,
                "criteria": self.criteria,
                "criteria_name": r.criteria_name, **r.estimate.as_dict(),
                "limiting": None if b is None else {
                    "ec": b.id, "name": b.name, "unit": b.unit, "n_fail": b.n_fail,
                    "failure_rate": b.failure_rate, "worst_value": b.worst_value,
                    "worst_margin": b.worst_margin},
                "nominal": None if r.nominal is None else r.nominal.ec.as_dict(),
                "worst_sample": r.worst_index,
                "ecs": [e.as_dict() for e in r.ecs],
                "yield_by_load": r.yield_by_load(),
                "scale_curve": [{"scale": p.scale, **p.estimate.as_dict()}
                                for p in r.scale_curve],
                "timings_s": {k: round(v, 3) for k, v in r.timings.items()}}


@dataclass(frozen=True)
class MarketsRobustness(YieldVerdict):
    """The yield of one setting in several markets: each market's
    (:class:`MarketYield`, in the order given) and the yield over all of them (a sample
    passes when it passes every market)."""

    scene_name: str
    scene_file: str
    params: IspParams
    output: OutputSpec
    variation: Variation
    seed: int
    samples: tuple[MountSample, ...]
    markets: tuple[MarketYield, ...]
    min_yield: float | None = None
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def passed(self) -> np.ndarray:
        """(n,) bool: the sample passes every market."""
        return np.logical_and.reduce([m.result.passed for m in self.markets])

    @property
    def estimate(self) -> YieldEstimate:
        """The all-markets yield with its 95 % interval."""
        return yield_estimate(self.passed)


    @property
    def judged_at(self) -> OutputSpec:
        """The RVM image of record (the first market's)."""
        return self.markets[0].result.judged_at or self.output

    def _sample_dict(self, i: int) -> dict[str, Any]:
        """One sample's row: its offsets and load, whether it passes every market, and per
        market its EC score, pass and failing ECs."""
        per: dict[str, dict[str, Any]] = {}
        failed: list[str] = []
        for m in self.markets:
            ev = m.result.evaluation
            fails = [e for e, ok in zip(ev.ids, ev.passed[i]) if not ok]
            per[m.name] = {"passed": bool(m.result.passed[i]), "ec_score": float(ev.score[i]),
                           "failed": fails}
            failed += [f"{m.name}:{e}" for e in fails]
        return {**self.samples[i].as_dict(), "passed": bool(self.passed[i]),
                "ec_score": min(float(p["ec_score"]) for p in per.values()),
                "failed": failed, "markets": per}

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (robustness.json): the all-markets yield at the top (``yield``,
        ``ci95``, ``n_pass``, ``n``), one row per market under ``markets``, every market's
        ECs under ``ecs`` (each with its ``market``) and the per-sample records."""
        rec = self.judged_at
        return {
            "scene": self.scene_file, "vehicle": self.scene_name,
            "criteria": "markets: " + ", ".join(m.name for m in self.markets),
            "isp": params_to_dict(self.params, self.output, judged_at=rec),
            "judged_at": [rec.width, rec.height], "seed": self.seed,
            "variation": self.variation.as_dict(), **self.estimate.as_dict(),
            "all_markets": self.estimate.as_dict(),
            "min_yield": self.min_yield, "meets_min_yield": self.meets_min_yield,
            "markets": [m.as_dict() for m in self.markets],
            "ecs": [{"market": m.name, **e.as_dict()} for m in self.markets
                    for e in m.result.ecs],
            "yield_by_load": _by_load(self.passed, self.samples),
            "compensation": None, "yield_before_compensation": None,
            "samples": [self._sample_dict(i) for i in range(len(self.samples))],
            "timings_s": {k: round(v, 3) for k, v in self.timings.items()},
        }

    def summary(self) -> str:
        """A few lines for the terminal: the all-markets yield, then one line per market
        with its yield and limiting EC."""
        est = self.estimate
        lo, hi = est.ci
        lines = [f"{self.scene_name}: yield over all markets {100 * est.yield_:.1f} % "
                 f"(95 % CI {100 * lo:.1f}–{100 * hi:.1f} %, {est.n_pass} of {est.n} "
                 "samples pass every market)"]
        width = max(len(m.name) for m in self.markets)
        for m in self.markets:
            e = m.result.estimate
            mlo, mhi = e.ci
            b = m.limiting
            bind = ("no EC fails" if b is None else
                    f"limiting EC {b.id} {b.name} fails on {100 * b.failure_rate:.1f} % "
                    f"(worst {_num(b.worst_value)} {b.unit})")
            lines.append(f"  {m.name:<{width}}  {100 * e.yield_:5.1f} % (95 % CI "
                         f"{100 * mlo:.1f}–{100 * mhi:.1f} %)  {bind}")
        return "\n".join(lines)


def _num(x: float | None) -> str:
    return "—" if x is None else f"{x:.3g}"


def markets_robustness(scene: Scene, params: IspParams, members: Sequence[MarketMember],
                       settings: RobustnessSettings = RobustnessSettings(), *,
                       runner: TaskRunner | None = None, frames: bool = True,
                       progress: bool = False) -> MarketsRobustness:
    """The yield of ``params`` over ``scene``'s production variation in every market.

    Parameters
    ----------
    scene : Scene
        The car (at its own site; its ``variation`` section is the default variation).
    params : IspParams
        For the full sensor.
    members : sequence of MarketMember
        :func:`rvmsim.markets.market_members` of ``[scene]``: each market's scene at its
        site and its criteria.
    settings : RobustnessSettings
        As for :func:`robustness`; ``criteria`` is each market's (the one given is not
        used) and ``compensation`` must be None.
    runner, frames, progress
        As for :func:`robustness`, per market.

    Returns
    -------
    MarketsRobustness

    Raises
    ------
    ValueError
        No members, or a compensation model in ``settings``.
    """
    if not members:
        raise ValueError("markets_robustness needs at least one market")
    if settings.compensation is not None:
        raise ValueError("markets_robustness: end-of-line compensation is not supported")
    t0 = time.perf_counter()
    var = settings.variation if settings.variation is not None else variation_from_scene(scene)
    out = []
    for m in members:  # the same variation and seed: the same samples in every market
        how = dataclasses.replace(settings, criteria=m.criteria, variation=var)
        res = robustness(m.scene, params, how, runner=runner, frames=frames,
                         progress=progress)
        out.append(MarketYield(m.market.name, m.market.title or m.market.name,
                               m.market.site, m.market.criteria, res))
    first = out[0].result
    timings = {f"{m.name}": m.result.timings.get("total", 0.0) for m in out}
    timings["total"] = time.perf_counter() - t0
    return MarketsRobustness(scene.name, scene.source, params, settings.output, var,
                             settings.seed, first.samples, tuple(out), settings.least_yield(var),
                             timings)
