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


def _verdict_results(pts, verdict_of):
    results = {}
    for p in pts:
        v = dict(p.values)
        kind = verdict_of(v)
        results[p.key] = {
            "score": 0.8 if kind == "pass" else 0.01, "passed": kind == "pass",
            "limiting_ec": None if kind == "pass" else "1-1", "evaluations": 1234,
            "verdict": kind, "reason": "1-1: object F's lower patch is outside the lens's "
                                      "field of view at this mount" if kind == "infeasible"
            else None,
            "infeasible": [{"ec": "1-1", "reason": "…", "short": "1-1: F out of view"}]
            if kind == "infeasible" else []}
    return results


def _colour_pixels(png: bytes, hex_rgb: str) -> int:
    img = cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR)
    bgr = [int(hex_rgb[i:i + 2], 16) for i in (5, 3, 1)]
    return int(np.all(np.abs(img.astype(int) - bgr) <= 2, axis=2).sum())


def test_map_shows_the_three_verdicts_distinctly():
    """pass / not found / infeasible per cell; over another axis a point not found beats an
    infeasible one; the map draws amber and grey only where those verdicts are."""
    spec = _spec(("a", "b"))
    pts = design_points(spec)

    def verdict(v):
        if v["a"] == 2 and v["b"] == 20:
            return "pass"
        if v["a"] == 1 and v["b"] == 10:
            return "infeasible"
        if v["a"] == 2 and v["b"] == 10:  # infeasible at c = x, not found at c = y
            return "infeasible" if v["c"] == "x" else "not found"
        return "not found"

    results = _verdict_results(pts, verdict)
    g = feasibility_grid(spec, pts, results)
    assert g.verdict.tolist() == [["infeasible", "not found"], ["not found", "pass"]]
    assert g.reason[0, 0] == "1-1: F out of view" and g.reason[0, 1] == ""
    assert (g.evaluations == 1234).all()
    png = feasibility_png(spec, pts, results)
    amber, grey = "#f3c77a", "#c8c8c8"
    only_pass = feasibility_png(spec, pts, _verdict_results(pts, lambda v: "pass"))
    for colour in (amber, grey):  # beyond the legend's swatch: cells of that colour
        assert _colour_pixels(png, colour) > 5 * _colour_pixels(only_pass, colour) + 1000
    # Results without verdicts (a store from before them): pass or not found.
    old = {k: {x: r[x] for x in ("score", "passed", "limiting_ec")} for k, r in results.items()}
    g_old = feasibility_grid(spec, pts, old)
    assert set(g_old.verdict.ravel()) == {"pass", "not found"}
