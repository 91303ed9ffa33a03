"""A sweep's results as data: the design-point table (``sweep.csv``) and ``sweep.json``
(:func:`rvmsim.report.write_sweep_outputs` writes them with the pictures and the page).

The table's EC columns are the ECs of the sweep's criteria, in their order; the yield
columns (:data:`~rvmsim.batch.yields.YIELD_COLUMNS`) are always there, empty for a point
without a yield.  A markets sweep (:mod:`rvmsim.batch.markets`) has every market's ECs,
a ``limiting_market`` column after ``limiting_ec`` and a ``pass_<market>`` column per
market before the EC columns.
"""

from __future__ import annotations

import csv
import io
import json
from typing import Any

from .payloads import MergedPoint, MergedResult, PointError, PointRun
from .run import SweepResult, phase_seconds
from .spec import DesignPoint, SweepSpec
from .markets import market_names
from .yields import YIELD_COLUMNS, yield_cells
from ..isp import IspParams

__all__ = ["Cell", "sweep_table", "csv_text", "sweep_json", "page_columns", "point_verdict"]

#: One cell of the design-point table (None: empty).
Cell = str | int | float | bool | None

#: Table columns between the axes and the EC columns.
_SCORE_COLUMNS = ("verdict", "ec_score", "passed", "limiting_ec", "reason")


def _score_columns(spec: SweepSpec) -> tuple[str, ...]:
    """The columns between the axes and the EC columns: :data:`_SCORE_COLUMNS`, and for a
    markets sweep ``limiting_market`` after ``limiting_ec`` and ``pass_<market>`` per
    market."""
    if not spec.markets:
        return _SCORE_COLUMNS
    return ("verdict", "ec_score", "passed", "limiting_ec", "limiting_market", "reason",
            *(f"pass_{m}" for m in market_names(spec.markets)))


def _score_cells(spec: SweepSpec, r: MergedPoint) -> list[Cell]:
    """A finished point's cells of :func:`_score_columns`."""
    cells: list[Cell] = [point_verdict(r), r["score"], r["passed"], r["limiting_ec"]]
    if not spec.markets:
        return [*cells, r.get("reason")]
    per = r.get("markets", {})
    return [*cells, r.get("limiting_market"), r.get("reason"),
            *(per[m]["passed"] if m in per else None for m in market_names(spec.markets))]


def sweep_table(spec: SweepSpec, points: list[DesignPoint], results: dict[str, MergedResult]
                ) -> tuple[list[str], list[list[Cell]]]:
    """(header, rows): one row per design point, in point order.

    Columns: ``point``, the axes, ``verdict`` (pass, not found, infeasible), ``ec_score``,
    ``passed``, ``limiting_ec``, ``reason`` (why infeasible), ``ec_<id>`` (pass/FAIL) per EC
    of the sweep's criteria (a markets sweep: ``limiting_market`` after ``limiting_ec``,
    ``pass_<market>`` (True/False) per market after ``reason``, every market's ECs), :data:`~rvmsim.batch.yields.YIELD_COLUMNS` (empty without a
    yield), the ISP parameters, ``evaluations`` (first pass and re-checks summed) and
    ``error``.  Deterministic content only (no timings), so the same sweep gives the same
    table on any executor.
    """

    ec_ids = spec.ec_ids()
    param_names = IspParams.names()
    scores = _score_columns(spec)
    header = ["point", *(n for n, _ in spec.axes), *scores,
              *[f"ec_{e}" for e in ec_ids], *YIELD_COLUMNS, *param_names, "evaluations",
              "error"]
    rows: list[list[Cell]] = []
    for p in points:
        r = results.get(p.key)
        vals = [json.dumps(v) if isinstance(v, list) else v for _, v in p.values]
        if r is None or "error" in r:
            rows.append([p.index, *vals, *[None] * len(scores), *[None] * len(ec_ids),
                         *[None] * len(YIELD_COLUMNS), *[None] * len(param_names), None,
                         "not run" if r is None else r["error"]])
            continue
        rows.append([p.index, *vals, *_score_cells(spec, r),
                     *[("pass" if r["ecs"][e]["passed"] else "FAIL") if e in r["ecs"] else None
                       for e in ec_ids],
                     *yield_cells(r), *[r["params"][n] for n in param_names], r["evaluations"], ""])
    return header, rows


def point_verdict(result: MergedPoint | PointRun | PointError) -> str | None:
    """A finished point's verdict (:data:`~rvmsim.batch.recheck.VERDICTS`); a run not
    merged (no re-check bookkeeping) passes or is ``not found``; None for an error."""
    if "error" in result:
        return None
    if "verdict" in result:
        return result["verdict"]
    return "pass" if result["passed"] else "not found"


def page_columns(spec: SweepSpec) -> int:
    """How many leading table columns the page shows: the point, the axes, the scores, the
    ECs and, when the sweep measures yields, the yield columns (the tuned parameters are in
    sweep.csv)."""
    yields = len(YIELD_COLUMNS) if spec.has_variation and spec.robustness.samples else 0
    return 1 + len(spec.axes) + len(_score_columns(spec)) + len(spec.ec_ids()) + yields


def csv_text(header: list[str], rows: list[list[Cell]]) -> str:
    """The table as CSV: None as an empty cell, floats in full (``repr``)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow(["" if v is None else (repr(v) if isinstance(v, float) else v) for v in row])
    return buf.getvalue()


def sweep_json(res: SweepResult) -> dict[str, Any]:
    """``sweep.json``'s document (JSON, to be dumped): the settings and every point's full
    result (with the
    :data:`~rvmsim.batch.yields.YIELD_COLUMNS` as keys where it has a yield; the details
    under ``robustness``)."""
    spec = res.spec
    return {"name": spec.name, "sweep_file": spec.source, "base_scene": str(spec.base_scene),
            "axes": [[n, list(v)] for n, v in spec.axes], "strategy": spec.strategy,
            "budget": spec.budget, "seed": spec.seed,
            **({"markets": list(market_names(spec.markets)),
                "market_specs": list(spec.markets)} if spec.markets else {}),
            "recheck": {"rounds": spec.recheck.rounds,
                        "budget_factor": spec.recheck.budget_factor,
                        "neighbours": spec.recheck.neighbours},
            "robustness": {"samples": spec.robustness.samples, "seed": spec.robustness.seed,
                           "variation": spec.has_variation},
            "phase_seconds": phase_seconds(res.results),
            "points": [_point_json(p, res.results.get(p.key)) for p in res.points]}



def _point_json(point: DesignPoint, result: MergedResult | None) -> dict[str, Any]:
    """One point's entry of ``sweep.json`` (JSON, to be dumped)."""
    out: dict[str, Any] = {"index": point.index, "values": dict(point.values),
                           **(result if result is not None else {"error": "not run"})}
    if result is not None and "error" not in result and "robustness" in result:
        cells = yield_cells(result)
        y = result["robustness"]
        if cells[0] is not None and "error" not in y:
            out.update(zip(YIELD_COLUMNS, cells))
            out["yield_limiting_driver"] = y.get("limiting_driver")
    return out
