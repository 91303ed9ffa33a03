"""The schema of ``best/markets.json`` (:func:`~rvmsim.tune.markets.write_market_results`) as
``rvmsim report``, ``signoff`` and ``tune`` read it back: the keys and types their readers use
(a key with a default may be absent; other keys are allowed).
``tests/bad_input/test_result_files.py`` checks that what a markets run writes validates."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from .._io import ReadModel

__all__ = ["MarketsFile"]


class _Binding(ReadModel):
    ec: str = "—"
    name: str = ""
    value: float | None = None
    unit: str = ""
    score: float | None = None
    margin: float | None = None


class _MarketRow(ReadModel):
    member: str
    market: str | None = None
    title: str | None = None
    vehicle: str | None = None
    ec_score: float
    passed: bool
    failing: list[str] = []
    binding: _Binding | None = None
    images: str = ""


class _Infeasible(ReadModel):
    member: str
    ec: str | None = None
    reason: str


class _ConflictEc(ReadModel):
    ec: str
    member: str | None = None
    fails_in: int
    of: int


class _Conflict(ReadModel):
    members: Annotated[list[str], Field(min_length=2, max_length=2)]
    ecs: list[_ConflictEc] = []


class MarketsFile(ReadModel):
    """``best/markets.json``: one row per market, and why no setting passes every one."""

    trial: int | None = None
    ec_score: float | None = None
    passed: bool | None = None
    searched: bool | None = None
    markets: Annotated[list[_MarketRow], Field(min_length=1)]
    infeasible: list[_Infeasible] = []
    conflicts: list[_Conflict] = []
    passes_alone: dict[str, int] = {}
