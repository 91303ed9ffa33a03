"""A sweep's outputs: the design-point table (``sweep.csv``), ``sweep.json``, and the
feasibility and sensitivity pictures and page (drawn by :mod:`rvmsim.report`).

The table's EC columns are the ECs of the sweep's criteria, in their order.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

from ..errors import RvmsimError
from .run import SweepResult
from .spec import DesignPoint, SweepSpec

__all__ = ["sweep_table", "csv_text", "sweep_json", "write_sweep_outputs"]

#: Table columns between the axes and the EC columns.
_SCORE_COLUMNS = ("ec_score", "passed", "limiting_ec")


def sweep_table(spec: SweepSpec, points: list[DesignPoint], results: dict[str, dict[str, Any]]
                ) -> tuple[list[str], list[list[Any]]]:
    """(header, rows): one row per design point, in point order.

    Columns: ``point``, the axes, ``ec_score``, ``passed``, ``limiting_ec``, ``ec_<id>``
    (pass/FAIL) per EC of the sweep's criteria, the ISP parameters, ``evaluations`` and
    ``error``.  Deterministic content only (no timings), so the same sweep gives the same
    table on any executor.
    """
    from ..isp import IspParams

    ec_ids = spec.criteria().ids
    param_names = IspParams.names()
    header = ["point", *(n for n, _ in spec.axes), *_SCORE_COLUMNS,
              *[f"ec_{e}" for e in ec_ids], *param_names, "evaluations", "error"]
    rows = []
    for p in points:
        r = results.get(p.key)
        vals = [json.dumps(v) if isinstance(v, list) else v for _, v in p.values]
        if r is None or "error" in r:
            rows.append([p.index, *vals, *[None] * len(_SCORE_COLUMNS), *[None] * len(ec_ids),
                         *[None] * len(param_names), None,
                         "not run" if r is None else r["error"]])
            continue
        rows.append([p.index, *vals, r["score"], r["passed"], r["limiting_ec"],
                     *["pass" if r["ecs"][e]["passed"] else "FAIL" for e in ec_ids],
                     *[r["params"][n] for n in param_names], r["evaluations"], ""])
    return header, rows


def _page_columns(spec: SweepSpec) -> int:
    """How many leading table columns the page shows: the point, the axes, the scores and
    the ECs (the tuned parameters are in sweep.csv)."""
    return 1 + len(spec.axes) + len(_SCORE_COLUMNS) + len(spec.criteria().ids)


def csv_text(header: list[str], rows: list[list[Any]]) -> str:
    """The table as CSV: None as an empty cell, floats in full (``repr``)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow(["" if v is None else (repr(v) if isinstance(v, float) else v) for v in row])
    return buf.getvalue()


def sweep_json(res: SweepResult) -> dict[str, Any]:
    """``sweep.json``'s document: the settings and every point's full result."""
    spec = res.spec
    return {"name": spec.name, "sweep_file": spec.source, "base_scene": str(spec.base_scene),
            "axes": [[n, list(v)] for n, v in spec.axes], "strategy": spec.strategy,
            "budget": spec.budget, "seed": spec.seed,
            "points": [{"index": p.index, "values": dict(p.values),
                        **res.results.get(p.key, {"error": "not run"})}
                       for p in res.points]}


def write_sweep_outputs(res: SweepResult) -> list[Path]:
    """Write sweep.csv, sweep.json, feasibility.png, sensitivity.png (when the sweep probed
    the sensitivity and some point scored) and sweep.html into ``res.out_dir``; returns the
    files written."""
    from ..report import feasibility_png, sensitivity_png, sweep_html
    from ..tune import json_default

    out = res.out_dir
    header, rows = sweep_table(res.spec, res.points, res.results)
    written = []
    try:
        (out / "sweep.csv").write_text(csv_text(header, rows))
        (out / "sweep.json").write_text(json.dumps(sweep_json(res), indent=1,
                                                   default=json_default))
        written += [out / "sweep.csv", out / "sweep.json"]
        feas = feasibility_png(res.spec, res.points, res.results)
        (out / "feasibility.png").write_bytes(feas)
        written.append(out / "feasibility.png")
        sens = sensitivity_png(res.points, res.results) if res.spec.sensitivity else None
        if sens is not None:
            (out / "sensitivity.png").write_bytes(sens)
            written.append(out / "sensitivity.png")
        html = sweep_html(res, header, rows, _page_columns(res.spec), feas, sens)
        (out / "sweep.html").write_text(html)
        written.append(out / "sweep.html")
    except OSError as err:
        raise RvmsimError(f"{out}: cannot write sweep outputs ({err.strerror or err})") from None
    return written
