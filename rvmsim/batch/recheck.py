"""Continuation over the grid, re-checks and the three verdicts of a design point.

After the first pass (every point tuned cold, in parallel), every point that did not pass
and is not proven infeasible (:mod:`rvmsim.batch.feasibility`) is *re-checked*: tuned again
with the budget times ``tune.recheck.budget_factor``, a seed of its own
(:func:`recheck_seed`), and warm-started from its own best parameters and those of its best
few grid neighbours (:func:`recheck_starts`).  Round 1 re-checks every such point; each
further round (up to ``tune.recheck.rounds``) re-checks the points still not passing that
neighbour a point the previous round turned to pass, so a pass spreads across the grid; the
rounds stop when one turns none.

Which points a round re-checks, and from where, depends only on the results of the earlier
rounds (all stored in ``sweep.sqlite``), so an interrupted sweep resumes to the results an
unbroken one gives.

Every point's final result (:func:`merge_point`) is its best run, with:

- ``verdict``: ``pass``; ``infeasible`` (a reason that needs no search, in ``reason``);
  or ``not found`` (no run passed, within ``evaluations``);
- ``evaluations``: summed over the first pass and all its re-checks.

Convention
----------
Neighbours are adjacent in axis-index space: every point whose value index differs by at
most one on every axis (diagonals included), the point itself excluded.
"""

from __future__ import annotations

import hashlib
import itertools
from collections.abc import Mapping, Sequence

import numpy as np

from .payloads import (InfeasibleDoc, MergedPoint, MergedResult, PointResult, PointRun,
                       PointTask, Verdict)
from .spec import DesignPoint, SweepSpec

__all__ = ["VERDICTS", "grid_index", "grid_neighbours", "recheck_seed", "merge_point",
           "merged_results", "recheck_points", "recheck_starts", "recheck_task",
           "recheck_task_key"]

#: A design point's verdicts.
VERDICTS = ("pass", "not found", "infeasible")


def grid_index(spec: SweepSpec, point: DesignPoint) -> tuple[int, ...]:
    """The point's value index on every axis, in the axes' order."""
    sizes = [len(v) for _, v in spec.axes]
    return tuple(int(i) for i in np.unravel_index(point.index, sizes))


def grid_neighbours(spec: SweepSpec, points: Sequence[DesignPoint]
                    ) -> dict[str, list[DesignPoint]]:
    """Point key → the points adjacent to it (see the module's Convention), in point
    order."""
    at = {grid_index(spec, p): p for p in points}
    steps = [d for d in itertools.product((-1, 0, 1), repeat=len(spec.axes)) if any(d)]
    out: dict[str, list[DesignPoint]] = {}
    for idx, p in at.items():
        near = [at[q] for q in (tuple(a + b for a, b in zip(idx, d)) for d in steps) if q in at]
        out[p.key] = sorted(near, key=lambda q: q.index)
    return out


def recheck_seed(seed: int, round_: int) -> int:
    """The search seed of re-check round ``round_`` (≥ 1) of a sweep seeded ``seed``: a
    fixed function of both, in 0 … 2³¹ − 1, unlike the first pass's."""
    digest = hashlib.sha256(f"rvmsim-recheck:{seed}:{round_}".encode()).digest()
    return int.from_bytes(digest[:4], "big") & 0x7FFFFFFF


def _rank(r: PointRun | MergedPoint) -> tuple[bool, float]:
    return (bool(r["passed"]), float(r["score"]))


def merge_point(first: PointResult,
                rechecks: Sequence[tuple[int, PointResult]] = ()) -> MergedResult:
    """A point's final result from its first-pass result and its re-checks ((round,
    result) pairs, in round order).

    The best run (a passing one first, then the highest score; the earliest of equals)
    gives the EC results, parameters, limiting EC and sensitivity.  Added: ``verdict``,
    ``reason`` (the infeasibility reasons, ``; ``-joined, for ``infeasible``; else None),
    ``evaluations`` (every run's, summed), ``rechecks`` (how many ran), ``found_in`` (0:
    the first pass, else the round of the best run) and ``first_pass`` (its ``score``,
    ``passed`` and ``evaluations``).  A point whose first pass failed to run (``error``)
    is returned as it is.
    """
    if "error" in first:
        return {**first}
    runs: list[tuple[int, PointRun]] = [(0, first)]
    runs += [(rnd, r) for rnd, r in rechecks if "error" not in r]
    found_in, best = runs[0]
    for rnd, r in runs[1:]:
        if _rank(r) > _rank(best):
            found_in, best = rnd, r
    infeasible: list[InfeasibleDoc] | None = next(
        (r["infeasible"] for _, r in reversed(runs) if "infeasible" in r), None)
    verdict: Verdict
    if best["passed"]:
        verdict = "pass"
    else:
        verdict = "infeasible" if infeasible else "not found"
    out: MergedPoint = {
        **best, "evaluations": sum(int(r["evaluations"]) for _, r in runs), "verdict": verdict,
        "reason": ("; ".join(x["reason"] for x in infeasible or ())
                   if verdict == "infeasible" else None),
        "rechecks": len(runs) - 1, "found_in": found_in,
        "first_pass": {"score": first["score"], "passed": first["passed"],
                       "evaluations": first["evaluations"]}}
    if infeasible is not None:
        out["infeasible"] = infeasible
    return out


def merged_results(points: Sequence[DesignPoint], done: Mapping[str, PointResult],
                   rechecks: Mapping[tuple[str, int], PointResult],
                   upto_round: int | None = None) -> dict[str, MergedResult]:
    """Every finished point's :func:`merge_point` by key, counting the re-checks of rounds
    ≤ ``upto_round`` (None: all)."""
    by_point: dict[str, list[tuple[int, PointResult]]] = {}
    for (key, rnd), r in sorted(rechecks.items(), key=lambda kv: kv[0][1]):
        if upto_round is None or rnd <= upto_round:
            by_point.setdefault(key, []).append((rnd, r))
    return {p.key: merge_point(done[p.key], by_point.get(p.key, ()))
            for p in points if p.key in done}


def recheck_points(points: Sequence[DesignPoint],
                   neighbours: Mapping[str, Sequence[DesignPoint]],
                   merged: Mapping[str, MergedResult],
                   turned: set[str] | None) -> list[DesignPoint]:
    """The points a round re-checks: those whose verdict is ``not found`` and, after the
    first round (``turned`` not None: the keys the previous round turned to pass), that
    neighbour one of ``turned``."""
    out = []
    for p in points:
        r = merged.get(p.key)
        if r is None or "error" in r or r["verdict"] != "not found":
            continue
        if turned is None or any(q.key in turned for q in neighbours[p.key]):
            out.append(p)
    return out


def recheck_starts(point: DesignPoint, neighbours: Sequence[DesignPoint],
                   merged: Mapping[str, MergedResult], most: int
                   ) -> list[dict[str, float]]:
    """The parameter sets a re-check of ``point`` starts from: its own best, then the best
    of up to ``most`` neighbours (passing first, then by score; ties in point order), each
    once."""
    runs = {k: r for k, r in merged.items() if "error" not in r}
    ranked = sorted((q for q in neighbours if q.key in runs),
                    key=lambda q: (not runs[q.key]["passed"], -runs[q.key]["score"], q.index))
    out: list[dict[str, float]] = []
    for q in [point, *ranked[:most]]:
        r = runs.get(q.key)
        if r is not None and r["params"] not in out:
            out.append(dict(r["params"]))
    return out


def recheck_task(base: PointTask, spec: SweepSpec, round_: int,
                 starts: list[dict[str, float]], best: MergedResult | None = None
                 ) -> PointTask:
    """The :func:`~rvmsim.batch.point.run_point` task of re-check round ``round_`` from the
    point's first-pass task ``base``; ``best``: the point's merged result over the earlier
    rounds (its rank is the task's ``beat``: the re-check measures a yield only when it
    beats it, and only then can it become the point's final best, :func:`merge_point`)."""
    task: PointTask = {**base, "seed": recheck_seed(spec.seed, round_),
                       "budget_factor": spec.recheck.budget_factor, "starts": starts}
    if best is not None and "error" not in best:
        task["beat"] = (bool(best["passed"]), float(best["score"]))
    return task


def recheck_task_key(point: DesignPoint, round_: int) -> str:
    """The executor key of re-check round ``round_`` of ``point``."""
    return f"{point.task_key}-r{round_}"
