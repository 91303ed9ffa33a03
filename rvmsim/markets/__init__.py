"""Markets: one setting for every market a car is sold in.

A *market* is a test site and the criteria judged there (:class:`Market`): FMVSS No. 111
for the US (``fmvss111-full``, or ``fmvss111`` for the paper's eleven ECs alone), UN
Regulation No. 158 for the EU, the other UN-1958 countries and Japan's law (``unr158``), and
Japan's rear-view monitor assessment where it asks more (``jp``).  ``--markets
fmvss111-full,unr158`` makes each market a *member* of the run
(:mod:`rvmsim.tune.members`): the scene at the market's site (:func:`rvmsim.scene.site_scene`,
rendered once and cached), judged with the market's criteria.  A setting passes when it
passes every market; the binding criterion of a market is its EC with the least score
(:func:`binding_ec`).  A market may also be given as ``SITE:CRITERIA`` (each a bundled
name or a file), e.g. ``./our_site.yaml:./our_criteria.yaml``.

Sources, the regulations' requirements and every ⚠ choice: docs/markets.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import RvmsimError
from ..scene import is_site_file, site_definition, site_scene
from ..criteria import load_criteria
from ..pipeline import record_output, render_rvm

if TYPE_CHECKING:
    from ..criteria import Criteria, EcValue
    from ..isp import IspParams
    from ..pipeline import RvmFrame
    from ..scene import Scene

__all__ = ["Market", "BUNDLED_MARKETS", "parse_markets", "market_scene", "market_criteria",
           "MarketMember", "market_members", "member_name", "MarketVerdict",
           "evaluate_markets", "binding_ec", "binding_row"]


@dataclass(frozen=True)
class Market:
    """A market: its name, its test site (a bundled site name or a site file) and its
    criteria (a bundled criteria set's name, a criteria file, or None for the paper's
    eleven ECs), and a title for tables."""

    name: str
    site: str
    criteria: str | None
    title: str = ""

    @property
    def spec(self) -> str:
        """What a run records: the name of a bundled market, else ``SITE:CRITERIA`` with
        absolute file paths (so a resume reads the same files from any folder)."""
        if BUNDLED_MARKETS.get(self.name) == self:
            return self.name
        return f"{self.site}:{self.criteria}"


#: Markets shipped with rvmsim.
BUNDLED_MARKETS: dict[str, Market] = {
    "fmvss111-full": Market("fmvss111-full", "fmvss111", "fmvss111-full",
                            "US: FMVSS No. 111 (the paper's ECs and S5.5)"),
    "fmvss111": Market("fmvss111", "fmvss111", None, "US: FMVSS No. 111 site, the paper's ECs"),
    "unr158": Market("unr158", "unr158", "unr158",
                     "EU, UN-1958 countries, Japan (law): UN R158 rear-view camera system"),
    "jp": Market("jp", "jp", "jp", "Japan: JNCAP rear-view monitor assessment"),
}


def _one(entry: str, base_dir: Path) -> Market:
    if entry in BUNDLED_MARKETS:
        return BUNDLED_MARKETS[entry]
    if ":" in entry:
        site, _, crit = entry.partition(":")
        if not site or not crit:
            raise RvmsimError(f"--markets {entry!r}: give SITE:CRITERIA (each a bundled name "
                              "or a file)")

        for part, is_file in ((site, is_site_file(site)),
                              (crit, crit.lower().endswith((".yaml", ".yml")))):
            if is_file and not (base_dir / part).is_file():
                raise RvmsimError(f"--markets {entry!r}: {base_dir / part}: no such file")
        return Market(entry, str(base_dir / site) if is_site_file(site) else site,
                      str(base_dir / crit) if crit.lower().endswith((".yaml", ".yml"))
                      else crit, entry)
    raise RvmsimError(f"--markets {entry!r}: unknown market (bundled: "
                      f"{', '.join(BUNDLED_MARKETS)}; or SITE:CRITERIA)")


def parse_markets(text: str | Sequence[str], base_dir: str | Path = ".") -> tuple[Market, ...]:
    """``fmvss111-full,unr158`` (or a list of names) → the markets, checked: known names
    or ``SITE:CRITERIA`` pairs, no repeats, at least one.  Files are relative to
    ``base_dir`` (the folder of the file that names them; the working folder on the
    command line).

    Raises
    ------
    RvmsimError
        One line naming ``--markets`` and the entry.
    """
    entries = ([e.strip() for e in text.split(",")] if isinstance(text, str)
               else [str(e).strip() for e in text])
    if not entries or any(not e for e in entries):
        raise RvmsimError(f"--markets {text!r}: give market names separated by commas "
                          f"(e.g. fmvss111-full,unr158; known: {', '.join(BUNDLED_MARKETS)})")
    dup = sorted({e for e in entries if entries.count(e) > 1})
    if dup:
        raise RvmsimError(f"--markets: {', '.join(dup)} given twice")
    markets = tuple(_one(e, Path(base_dir)) for e in entries)

    for m in markets:  # the site and the criteria load (one line each when they do not)
        market_criteria(m)
        site_definition(m.site)
    return markets


def market_scene(scene: Scene, market: Market) -> Scene:
    """``scene`` at the market's site (:func:`rvmsim.scene.site_scene`; a bundled site by
    name, so that a site file of the scene's own under that name replaces it)."""

    return site_scene(scene, site_definition(market.site) if is_site_file(market.site)
                      else market.site)


def market_criteria(market: Market) -> Criteria:
    """The market's criteria (:func:`rvmsim.criteria.load_criteria`)."""

    return load_criteria(market.criteria)


def member_name(scene: Scene, market: Market, n_scenes: int) -> str:
    """A member's name: the market, with the vehicle's name before it when a run has
    several vehicles."""
    return market.name if n_scenes == 1 else f"{scene.name} · {market.name}"


@dataclass(frozen=True)
class MarketMember:
    """One (vehicle, market) of a run: the scene at the market's site and its criteria."""

    name: str
    market: Market
    scene: Scene
    criteria: Criteria


def market_members(scenes: Sequence[Scene], markets: Sequence[Market]) -> list[MarketMember]:
    """Every (scene, market) pair, scene by scene, markets in the order given."""
    return [MarketMember(member_name(sc, m, len(scenes)), m, market_scene(sc, m),
                         market_criteria(m))
            for sc in scenes for m in markets]


@dataclass(frozen=True)
class MarketVerdict:
    """One market's verdict on one setting: its member, the evaluated frame (at the RVM
    image of record) and the binding criterion (the enabled EC with the least score)."""

    member: MarketMember
    frame: RvmFrame

    @property
    def passed(self) -> bool:
        return bool(self.frame.ec.passed)

    @property
    def binding(self) -> EcValue | None:
        return binding_ec(self.frame.ec.items)

    @property
    def failing(self) -> list[str]:
        return [e.id for e in self.frame.ec.items if e.enabled and not e.passed]

    def row(self) -> str:
        """``market  EC score  pass/FAIL  binding EC = value`` for terminals."""
        b = self.binding
        value = "—" if b is None or b.value is None else f"{b.value:.4g}{b.unit}"
        tail = "" if self.passed else f"; fails {', '.join(self.failing)}"
        return (f"{self.member.name:<24} {self.frame.ec.score:>8.4g}  "
                f"{'pass' if self.passed else 'FAIL':<6}  "
                f"{'—' if b is None else f'{b.id} {b.name}'} = {value}{tail}")


def binding_ec(items: Sequence[EcValue]) -> EcValue | None:
    """A market's binding criterion: its enabled EC with the least score (ties: the least
    margin), the one that limits a setting there; None without an enabled EC."""
    enabled = [e for e in items if e.enabled]
    if not enabled:
        return None
    return min(enabled, key=lambda e: (e.score, e.margin if e.margin is not None else 0.0))


def binding_row(items: Sequence[EcValue]) -> dict[str, object] | None:
    """The binding criterion as ``markets.json`` holds it: ``ec``, ``name``, ``value``,
    ``unit``, ``score``, ``margin`` (None without an enabled EC)."""
    worst = binding_ec(items)
    if worst is None:
        return None
    return {"ec": worst.id, "name": worst.name, "value": worst.value, "unit": worst.unit,
            "score": worst.score, "margin": worst.margin}


def evaluate_markets(scene: Scene, params: IspParams, markets: Sequence[Market], *,
                     mirror: bool = True, scale: float = 1.0, progress: bool = False
                     ) -> list[MarketVerdict]:
    """One ISP setting judged in every market: the scene rendered at each market's site
    (``scale`` of the sensor) and evaluated with the market's criteria at the RVM image of
    record (:func:`rvmsim.pipeline.record_output`), annotated.

    Parameters
    ----------
    scene : Scene
        The car (at its FMVSS site, as loaded).
    params : IspParams
        The setting, for the full-size sensor.
    markets : sequence of Market
    mirror : bool
        Whether the RVM image is mirrored.
    """

    out = []
    for member in market_members([scene], markets):
        record = record_output(member.criteria, member.scene, mirror)
        frame = render_rvm(member.scene, params, record, criteria=member.criteria, scale=scale,
                           annotate=True, progress=progress)
        out.append(MarketVerdict(member, frame))
    return out
