"""The sweep page: the feasibility map, the sensitivity chart and the design-point table of a
design-stage sweep (:mod:`rvmsim.batch`), on one self-contained HTML page.

The map shows each cell's verdict (:data:`rvmsim.batch.VERDICTS`): *pass* cells green
(darker for a higher score) inside a black outline, *not found* cells amber with the best
score and the limiting EC, *infeasible* cells grey and hatched with a short reason.  When
the sweep measured yields (:mod:`rvmsim.batch.yields`), the yield map beside it shows the
yield of the same point per cell, with its 95 % interval and the EC failing most often.

A markets sweep (``tune.markets``) shows a cell as *pass* only when every market passes;
the map's title and legend name the markets, and a limiting EC names its market.

Convention: the feasibility map's cell (i, j) is the j-th value of its x axis and the i-th
of its y axis, drawn with the origin at the lower left; cells are 1 unit wide, centred on
integers.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.colors import ListedColormap, Normalize
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from ..batch import (VERDICTS, Cell, DesignPoint, MergedPoint, MergedResult, SweepResult,
                     SweepSpec, csv_text, market_names, page_columns, point_verdict, sweep_json,
                     sweep_table, yield_cells)
from ..errors import RvmsimError
from ..storage import json_default
from .page import data_uri, escape, figure_png, page

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["FeasibilityGrid", "feasibility_grid", "feasibility_png", "yield_png",
           "sensitivity_png", "sweep_html", "write_sweep_outputs"]


@dataclass(frozen=True)
class FeasibilityGrid:
    """The feasibility map's cells: per (y, x) value, the best point over the other axes
    (passing first, then not found before infeasible, then by score): its score, whether it
    passes every EC, its limiting EC ("" when it passes or has none), its verdict ("" where
    no point finished), a short reason ("" unless infeasible), its evaluations, its yield
    (NaN without one), the yield's 95 % interval and the EC failing on most samples.

    ``y_axis`` is None for a one-axis map (one row, ``ys == [None]``); ``others`` are the
    other axes with several values, which the map takes the best over.  ``xs`` and ``ys``
    are axis values as the sweep file gives them.
    """

    x_axis: str
    y_axis: str | None
    xs: list[Any]
    ys: list[Any]
    score: np.ndarray  # (len(ys), len(xs)) float, NaN where no point finished
    passed: np.ndarray  # (len(ys), len(xs)) bool
    limiting: np.ndarray  # (len(ys), len(xs)) object (str)
    others: list[str]
    verdict: np.ndarray  # (len(ys), len(xs)) object (str)
    reason: np.ndarray  # (len(ys), len(xs)) object (str): a short reason where infeasible
    evaluations: np.ndarray  # (len(ys), len(xs)) int, 0 where no point finished
    yield_: np.ndarray | None = None  # (len(ys), len(xs)) float, NaN where no yield
    yield_ci: np.ndarray | None = None  # (len(ys), len(xs), 2) float, NaN where no yield
    yield_ec: np.ndarray | None = None  # (len(ys), len(xs)) object (str): "" where none


def _map_axes(spec: SweepSpec) -> tuple[str, str | None]:
    """The map's x and y axes: the sweep's ``map``, else its first two axes with several
    values (or its first axis)."""
    if spec.map_axes is not None:
        return spec.map_axes
    multi = [n for n, v in spec.axes if len(v) > 1] or [spec.axes[0][0]]
    return multi[0], (multi[1] if len(multi) > 1 else None)


def feasibility_grid(spec: SweepSpec, points: list[DesignPoint],
                     results: Mapping[str, MergedResult]) -> FeasibilityGrid:
    """Verdict, best score, pass, limiting EC and reason on the map's grid, best over the
    other axes (a passing point beats a failing one with a higher score, and a point not
    found beats an infeasible one)."""
    axes = dict(spec.axes)
    xa, ya = _map_axes(spec)
    xs = list(axes[xa])
    ys = list(axes[ya]) if ya is not None else [None]
    shape = (len(ys), len(xs))
    score = np.full(shape, np.nan)
    passed = np.zeros(shape, bool)
    limiting = np.full(shape, "", dtype=object)
    verdict = np.full(shape, "", dtype=object)
    reason = np.full(shape, "", dtype=object)
    evaluations = np.zeros(shape, int)
    yield_, yield_ci = np.full(shape, np.nan), np.full(shape + (2,), np.nan)
    yield_ec = np.full(shape, "", dtype=object)
    best: dict[tuple[int, int], tuple[bool, bool, float]] = {}
    for p in points:
        r = results.get(p.key)
        if r is None or "error" in r:
            continue
        v = dict(p.values)
        i = ys.index(v[ya]) if ya is not None else 0
        j = xs.index(v[xa])
        kind = point_verdict(r) or ""
        rank = (bool(r["passed"]), kind != "infeasible", float(r["score"]))
        if (i, j) in best and rank <= best[(i, j)]:
            continue
        best[(i, j)] = rank
        score[i, j], passed[i, j] = r["score"], r["passed"]
        limiting[i, j] = _limiting_text(r)
        verdict[i, j] = kind
        reason[i, j] = _short_reason(r) if kind == "infeasible" else ""
        evaluations[i, j] = r.get("evaluations", 0)
        y, lo, hi, y_ec = yield_cells(r)[:4]
        yield_[i, j] = np.nan if y is None else y
        yield_ci[i, j] = (np.nan, np.nan) if y is None else (lo, hi)
        yield_ec[i, j] = y_ec or ""
    others = [n for n, v in spec.axes if n not in (xa, ya) and len(v) > 1]
    return FeasibilityGrid(xa, ya, xs, ys, score, passed, limiting, others, verdict, reason,
                           evaluations, yield_, yield_ci, yield_ec)


def _limiting_text(r: MergedPoint) -> str:
    """The limiting EC as a cell shows it: ``R158-2``, in a markets sweep ``unr158
    R158-2`` ("" when none)."""
    ec, market = r["limiting_ec"], r.get("limiting_market")
    return "" if not ec else f"{market} {ec}" if market else ec


def _markets_text(spec: SweepSpec) -> str:
    """``fmvss111-full + unr158`` for a markets sweep, else ""."""
    return " + ".join(market_names(spec.markets)) if spec.markets else ""


def _short_reason(r: MergedPoint) -> str:
    """A few words on why a point is infeasible (its first reason's short form)."""
    inf = r.get("infeasible")
    short = inf[0].get("short") if inf else None
    return str(short or (r.get("reason") or "")[:24])


def _outline_passing(ax: Axes, passed: np.ndarray) -> None:
    """Draw the border of the passing cells: every cell edge with a non-passing (or no)
    neighbour."""
    rows, cols = passed.shape
    for i, j in zip(*np.nonzero(passed)):
        for di, dj, seg in ((1, 0, ([j - .5, j + .5], [i + .5, i + .5])),
                            (-1, 0, ([j - .5, j + .5], [i - .5, i - .5])),
                            (0, 1, ([j + .5, j + .5], [i - .5, i + .5])),
                            (0, -1, ([j - .5, j - .5], [i - .5, i + .5]))):
            ni, nj = i + di, j + dj
            if not (0 <= ni < rows and 0 <= nj < cols and passed[ni, nj]):
                ax.plot(*seg, color="black", linewidth=2.5)


#: Map colours: not found (amber), infeasible (grey), not run (white); pass is green-scaled.
_NOT_FOUND, _INFEASIBLE, _NOT_RUN = "#f3c77a", "#c8c8c8", "#ffffff"


def _cell_text(g: FeasibilityGrid, i: int, j: int) -> str:
    """What a map cell says: score and "pass"; score, limiting EC and evaluations; or
    "infeasible" and the short reason."""
    s, kind = g.score[i, j], g.verdict[i, j]
    if np.isnan(s):
        return "—"
    if kind == "pass":
        return f"{s:.2f}\npass"
    if kind == "infeasible":
        return "infeasible\n" + "\n".join(str(g.reason[i, j]).split(": ", 1))
    return f"not found\n{s:.2g} {g.limiting[i, j]}\n{g.evaluations[i, j]} evals"


def feasibility_png(spec: SweepSpec, points: list[DesignPoint],
                    results: Mapping[str, MergedResult]) -> bytes:
    """The feasibility map over the map's two axes (PNG bytes): pass cells green-scaled by
    score, the pass region outlined in black; not-found cells amber with the best score,
    the limiting EC and the evaluations spent; infeasible cells grey and hatched with a
    short reason; a legend below."""

    g = feasibility_grid(spec, points, results)
    fig = Figure(figsize=(2.4 + 1.25 * len(g.xs), 2.2 + 0.9 * len(g.ys)))
    ax = fig.add_subplot(111)
    greens = ListedColormap(colormaps["Greens"](np.linspace(0.25, 1.0, 256)))
    for i in range(len(g.ys)):
        for j in range(len(g.xs)):
            kind = g.verdict[i, j]
            face = (greens(float(g.score[i, j])) if kind == "pass"
                    else _NOT_FOUND if kind == "not found"
                    else _INFEASIBLE if kind == "infeasible" else _NOT_RUN)
            ax.add_patch(Rectangle((j - .5, i - .5), 1, 1, facecolor=face, edgecolor="#888",
                                   linewidth=0.5, hatch="///" if kind == "infeasible" else None))
            dark = kind == "pass" and g.score[i, j] > 0.6
            ax.text(j, i, _cell_text(g, i, j), ha="center", va="center", fontsize=7,
                    color="white" if dark else "black")
    _outline_passing(ax, g.passed)
    _axes_ticks(ax, g)
    fig.colorbar(ScalarMappable(Normalize(0.0, 1.0), greens), ax=ax,
                 label="EC score of passing cells")
    markets = _markets_text(spec)
    ax.legend(handles=[Patch(facecolor=greens(0.7), edgecolor="black",
                             label="pass" + (" (every market)" if markets else "")),
                       Patch(facecolor=_NOT_FOUND, label="not found (best score, limiting "
                                                         "EC, evaluations)"),
                       Patch(facecolor=_INFEASIBLE, hatch="///",
                             label="infeasible (reason; no search needed)")],
              loc="upper center", bbox_to_anchor=(0.5, -0.12 if g.y_axis else -0.3),
              ncol=3, fontsize=7, frameon=False)
    title = "feasibility: pass region outlined"
    if markets:
        title += f"\nmarkets: {markets} (pass: all pass)"
    if g.others:
        title += f"\n(best over {', '.join(g.others)})"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return figure_png(fig)


def _axes_ticks(ax: Axes, g: FeasibilityGrid) -> None:
    """The map's limits, ticks and axis names."""
    ax.set_xlim(-.5, len(g.xs) - .5)
    ax.set_ylim(-.5, len(g.ys) - .5)
    ax.set_xticks(range(len(g.xs)), [str(x) for x in g.xs])
    ax.set_xlabel(g.x_axis)
    if g.y_axis is not None:
        ax.set_yticks(range(len(g.ys)), [str(y) for y in g.ys])
        ax.set_ylabel(g.y_axis)
    else:
        ax.set_yticks([])


def yield_png(spec: SweepSpec, points: list[DesignPoint],
              results: Mapping[str, MergedResult]) -> bytes | None:
    """The yield map (PNG bytes): per cell of the feasibility map, the yield of the point
    that map shows there (red 0 % to green 100 %), its 95 % interval and the EC failing on
    most samples; the pass region outlined as on the feasibility map.  None when no point
    has a yield."""
    g = feasibility_grid(spec, points, results)
    if g.yield_ is None or g.yield_ci is None or g.yield_ec is None or np.isnan(g.yield_).all():
        return None


    cmap = colormaps["RdYlGn"]
    fig = Figure(figsize=(2.4 + 1.25 * len(g.xs), 2.2 + 0.9 * len(g.ys)))
    ax = fig.add_subplot(111)
    for i in range(len(g.ys)):
        for j in range(len(g.xs)):
            y = g.yield_[i, j]
            ax.add_patch(Rectangle((j - .5, i - .5), 1, 1, linewidth=0.5, edgecolor="#888",
                                   facecolor=_NOT_RUN if np.isnan(y) else cmap(float(y))))
            lo, hi = g.yield_ci[i, j]
            text = ("—" if np.isnan(y) else f"{100 * y:.0f} %\n[{100 * lo:.0f}–{100 * hi:.0f}]"
                    + (f"\n{g.yield_ec[i, j]}" if g.yield_ec[i, j] else ""))
            ax.text(j, i, text, ha="center", va="center", fontsize=7,
                    color="white" if not np.isnan(y) and not 0.2 <= y <= 0.85 else "black")
    _outline_passing(ax, g.passed)
    _axes_ticks(ax, g)
    fig.colorbar(ScalarMappable(Normalize(0.0, 1.0), cmap), ax=ax,
                 label="yield (share of samples passing every EC)")
    title = (f"yield over production variation ({spec.robustness.samples} samples)\n"
             "[95 % interval]; the EC failing most")
    if g.others:
        title += " (points as on the feasibility map)"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return figure_png(fig)


def sensitivity_png(points: list[DesignPoint], results: Mapping[str, MergedResult]
                    ) -> bytes | None:
    """Per ISP parameter: the relative EC score drop at ±5 % of its range around each design
    point's optimum (median and maximum over the passing points, or over all scoring points
    when none passes), and the score curves of the best point (PNG bytes; None when no point
    has a sensitivity probe and a score above 0)."""

    runs = [r for r in (results.get(p.key) for p in points)
            if r is not None and "error" not in r]
    rs = [r for r in runs if "sensitivity" in r and r["score"] > 0]
    if not rs:
        return None
    if any(r["passed"] for r in rs):  # where the design works is where tuning matters
        rs = [r for r in rs if r["passed"]]
    names = list(rs[0]["sensitivity"]["params"])
    drops = np.array([[r["sensitivity"]["params"][n]["drop_5pct"] or 0.0 for n in names]
                      for r in rs])
    best = max(rs, key=lambda r: r["score"])
    fig = Figure(figsize=(10, 3.8))
    ax = fig.add_subplot(121)
    med = np.median(drops, axis=0)
    order = np.argsort(-med)
    ax.barh([names[k] for k in order][::-1], med[order][::-1], color="#4a7bb7", xerr=None)
    ax.scatter(drops.max(axis=0)[order][::-1], range(len(names)), marker="|", color="black",
               label="max over points")
    ax.set_xlabel("EC score drop at ±5 % of range (median; < 0: a better point is near,\n"
                  "the tuning budget was short)", fontsize=8)
    ax.legend(fontsize=8)
    ax2 = fig.add_subplot(122)
    steps = best["sensitivity"]["steps"]
    half = len(steps) // 2
    xs = [*steps[:half], 0.0, *steps[half:]]
    for n in names:
        sc = best["sensitivity"]["params"][n]["scores"]
        ys = [*sc[:half], best["sensitivity"]["optimum"], *sc[half:]]
        ax2.plot([100 * x for x, y in zip(xs, ys) if y is not None],
                 [y for y in ys if y is not None], marker=".", label=n)
    ax2.set_xlabel("offset from the optimum, % of the parameter's range")
    ax2.set_ylabel("EC score (best design point)")
    ax2.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return figure_png(fig)


def _cell_class(v: Cell) -> str:
    """Table cell colour class (the page kit's CSS): pass/True green, FAIL/False and "not
    found" red, "infeasible" grey, anything else plain (the point numbers 0 and 1 too)."""
    if v == "pass" or v is True:
        return "pass"
    if v in ("FAIL", "not found") or v is False:
        return "fail"
    if v == "infeasible":
        return "off"
    return ""


def _cell(v: Cell) -> str:
    text = "" if v is None else (f"{v:.4g}" if isinstance(v, float) else v)
    return f'<td class="{_cell_class(v)}">{escape(text)}</td>'


def sweep_html(res: SweepResult, header: list[str], rows: list[list[Cell]], columns: int,
               feasibility: bytes, sensitivity: bytes | None,
               yield_map: bytes | None = None) -> str:
    """The sweep page: settings, the feasibility map, the yield map beside it (when given)
    and the sensitivity chart (PNG bytes), and the first ``columns`` columns of the
    design-point table (``header``, ``rows`` as :func:`rvmsim.batch.sweep_table` gives
    them)."""
    spec = res.spec
    counts = {k: 0 for k in VERDICTS}
    for r in res.results.values():
        kind = point_verdict(r)
        if kind is not None:
            counts[kind] += 1
    table = "".join("<tr>" + "".join(_cell(v) for v in row[:columns]) + "</tr>"
                    for row in rows)
    head = "".join(f"<th>{escape(h)}</th>" for h in header[:columns])
    sizes = " × ".join(f"{len(v)} {n}" for n, v in spec.axes)
    sens = ("" if sensitivity is None else
            "<h2>Sensitivity to the ISP parameters around the optimum</h2>"
            f'<img src="{data_uri(sensitivity)}" alt="sensitivity">')
    yields = "" if yield_map is None else f'<img src="{data_uri(yield_map)}" alt="yield map">'
    rob = spec.robustness
    markets = _markets_text(spec)
    every = f"every EC of every market ({markets})" if markets else "every EC"
    yield_text = ("" if yield_map is None else
                  f"<p class=\"muted\"><b>yield</b>: the share of {rob.samples} production "
                  f"variation samples (seed {rob.seed}; the scene's variation section) on which "
                  f"the point's best setting passes {escape(every)}, with its 95 % Wilson "
                  "interval; "
                  "yield_limiting_ec fails on most samples, yield_limiting_axis drives its "
                  "failures.</p>")
    return page(f"Sweep: {spec.name}", f"""
<h1>Feasibility sweep: {escape(spec.name)}</h1>
<p>Base scene {escape(spec.base_scene)}; {len(res.points)} design points
({escape(sizes)}); tuning: {escape(spec.strategy)},
budget {escape(spec.budget)}, seed {escape(spec.seed)}{
"; markets " + escape(markets) + ", each point tuned for all at once" if markets else ""}; re-check: up to
{escape(spec.recheck.rounds)} rounds at {escape(spec.recheck.budget_factor)}× the budget from
the best of up to {escape(spec.recheck.neighbours)} neighbours. Of {len(res.results)} finished
points, {counts["pass"]} pass {escape(every)}, {counts["not found"]} not found, {counts["infeasible"]}
infeasible.</p>
<h2>Feasibility map{" and yield" if yield_map is not None else ""}</h2>
<div style="display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start">
<img src="{data_uri(feasibility)}" alt="feasibility map">{yields}</div>
<p class="muted"><b>pass</b>: tuned to pass {escape(every)}. <b>not found</b>: no passing setting was
found within the evaluations shown (first pass and re-checks from the neighbours' optima); it
may still exist. <b>infeasible</b>: no ISP setting can pass, for a reason that needs no search
(the reason column).</p>
{yield_text}
{sens}
<h2>Design points</h2><p>Tuned parameters per point: sweep.csv.</p>
<table><tr>{head}</tr>{table}</table>
""")


def write_sweep_outputs(res: SweepResult) -> list[Path]:
    """Write sweep.csv, sweep.json, feasibility.png, sensitivity.png (when the sweep probed
    the sensitivity and some point scored), yield.png (when some point has a yield) and
    sweep.html into ``res.out_dir``; returns the
    files written.

    Raises
    ------
    RvmsimError
        One line naming the folder when a file cannot be written.
    """
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
        ymap = yield_png(res.spec, res.points, res.results)
        if ymap is not None:
            (out / "yield.png").write_bytes(ymap)
            written.append(out / "yield.png")
        html = sweep_html(res, header, rows, page_columns(res.spec), feas, sens, ymap)
        (out / "sweep.html").write_text(html)
        written.append(out / "sweep.html")
    except OSError as err:
        raise RvmsimError(f"{out}: cannot write sweep outputs ({err.strerror or err})") from None
    return written
