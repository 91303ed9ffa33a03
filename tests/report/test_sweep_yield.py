"""report.sweep: the yield map and the yield columns of the sweep page, from known
design-point results."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import cv2
import numpy as np

from rvmsim.batch import (YIELD_COLUMNS, SweepResult, SweepSpec, design_points, page_columns,
                          sweep_table)
from rvmsim.isp import IspParams
from rvmsim.report import feasibility_grid, feasibility_png, sweep_html, yield_png


def _spec(has_variation: bool = True) -> SweepSpec:
    spec = SweepSpec("m", "m.yaml", Path("b.yaml"), {}, (("a", (1, 2)), ("b", (10, 20)),
                                                         ("c", ("x", "y"))),
                     "cmaes", 10, 0, {}, None, ("a", "b"), False)
    return dataclasses.replace(spec, has_variation=has_variation)


def _results(pts, with_yield: bool = True):
    """Point c=y scores higher everywhere (the map shows it); its yield is a/2 (50 %, 100 %),
    c=x has yield 0 (never shown)."""
    ec_ids = _spec().criteria().ids
    out = {}
    for p in pts:
        v = dict(p.values)
        shown = v["c"] == "y"
        r = {"score": 0.5 + 0.1 * shown, "passed": True, "limiting_ec": None,
             "evaluations": 10, "verdict": "pass", "params": {n: 0.0 for n in IspParams.names()},
             "ecs": {e: {"passed": True} for e in ec_ids}}
        if with_yield:
            y = v["a"] / 2 if shown else 0.0
            r["robustness"] = {"yield": y, "ci95": [max(0.0, y - 0.1), min(1.0, y + 0.05)],
                               "n": 20, "n_pass": int(20 * y), "seed": 0,
                               "limiting_ec": None if y == 1 else "2-3",
                               "limiting_fail_rate": None if y == 1 else 1 - y,
                               "limiting_axis": None if y == 1 else "roll_deg",
                               "limiting_driver": None, "failure_rates": {}}
        out[p.key] = r
    return out


def _pixels_near(png: bytes, bgr: tuple[int, int, int], tol: int = 3) -> int:
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    return int(np.all(np.abs(img.astype(int) - bgr) <= tol, axis=2).sum())


def test_yield_map_shows_the_yield_of_the_feasibility_maps_point():
    spec = _spec()
    pts = design_points(spec)
    results = _results(pts)
    g = feasibility_grid(spec, pts, results)
    np.testing.assert_allclose(g.yield_, [[0.5, 1.0], [0.5, 1.0]])  # c = y's, not c = x's
    assert g.yield_ec.tolist() == [["2-3", ""], ["2-3", ""]]
    np.testing.assert_allclose(g.yield_ci[..., 0], [[0.4, 0.9], [0.4, 0.9]])
    np.testing.assert_allclose(g.yield_ci[..., 1], [[0.55, 1.0], [0.55, 1.0]])
    png = yield_png(spec, pts, results)
    assert png is not None
    # The 100 % column is green, the 50 % one yellowish: both cover whole cells.
    all_red = yield_png(spec, pts, {k: {**r, "robustness": {**r["robustness"], "yield": 0.0}}
                                    for k, r in results.items()})
    from matplotlib import colormaps

    def bgr(y):
        r, g_, b, _ = colormaps["RdYlGn"](y)
        return int(255 * b), int(255 * g_), int(255 * r)

    assert _pixels_near(png, bgr(1.0)) > 3 * _pixels_near(all_red, bgr(1.0)) + 2000
    assert _pixels_near(all_red, bgr(0.0)) > 3 * _pixels_near(png, bgr(0.0)) + 2000


def test_no_yield_no_map_and_no_page_columns():
    spec = _spec(has_variation=False)
    pts = design_points(spec)
    results = _results(pts, with_yield=False)
    assert yield_png(spec, pts, results) is None
    assert np.isnan(feasibility_grid(spec, pts, results).yield_).all()
    header, rows = sweep_table(spec, pts, results)
    cols = page_columns(spec)
    assert not set(YIELD_COLUMNS) & set(header[:cols])  # the page leaves them out
    assert set(YIELD_COLUMNS) <= set(header)  # sweep.csv keeps them (empty)
    assert all(row[header.index("yield")] is None for row in rows)


def test_page_shows_the_yield_map_and_columns():
    spec = _spec()
    pts = design_points(spec)
    results = _results(pts)
    header, rows = sweep_table(spec, pts, results)
    cols = page_columns(spec)
    assert set(YIELD_COLUMNS) <= set(header[:cols])
    res = SweepResult(spec, pts, results, 0, Path("."))
    feas = feasibility_png(spec, pts, results)
    ymap = yield_png(spec, pts, results)
    html = sweep_html(res, header, rows, cols, feas, None, ymap)
    assert 'alt="yield map"' in html and "<th>yield</th>" in html
    assert "<th>yield_limiting_axis</th>" in html and ">roll_deg<" in html
    plain = sweep_html(res, header, rows, cols, feas, None)
    assert "yield map" not in plain
