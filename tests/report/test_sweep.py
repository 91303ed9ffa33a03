"""report.sweep: the feasibility grid and map from known design-point results."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from rvmsim.batch import SweepSpec, design_points
from rvmsim.report import feasibility_grid, feasibility_png, sensitivity_png


def _spec(map_axes):
    return SweepSpec("m", "m.yaml", Path("b.yaml"), {}, (("a", (1, 2)), ("b", (10, 20)),
                                                         ("c", ("x", "y"))),
                     "cmaes", 10, 0, {}, None, map_axes, False)


def test_map_takes_the_best_over_other_axes_and_outlines_passing_cells():
    """The feasibility grid from known results: best over a third axis, pass flags and the
    limiting EC per cell."""
    spec = _spec(("a", "b"))
    pts = design_points(spec)
    results = {}
    for p in pts:
        v = dict(p.values)
        score = 0.1 * v["a"] + 0.01 * v["b"] / 10 + (0.5 if v["c"] == "y" else 0.0)
        passed = v["a"] == 2 and v["c"] == "y"
        results[p.key] = {"score": score, "passed": passed, "limiting_ec": None if passed else "2-1"}
    g = feasibility_grid(spec, pts, results)
    assert (g.x_axis, g.y_axis, g.others) == ("a", "b", ["c"])
    assert (g.xs, g.ys) == ([1, 2], [10, 20])
    np.testing.assert_allclose(g.score, [[0.61, 0.71], [0.62, 0.72]])
    assert g.passed.tolist() == [[False, True], [False, True]]
    assert g.limiting.tolist() == [["2-1", ""], ["2-1", ""]]
    png = feasibility_png(spec, pts, results)
    assert cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR) is not None
    assert sensitivity_png(pts, results) is None  # no point was probed


def test_default_map_axes_and_points_without_results():
    """Without ``map``: the first two axes with several values; a point with no result (or an
    error) leaves its cell empty."""
    spec = _spec(None)
    pts = design_points(spec)
    results = {pts[0].key: {"error": "boom"}}
    g = feasibility_grid(spec, pts, results)
    assert (g.x_axis, g.y_axis) == ("a", "b")
    assert np.isnan(g.score).all() and not g.passed.any()
