"""EC margins on one scale (rvmsim.percar.margins), computed by hand from the sigmoids."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rvmsim.criteria import default_criteria
from rvmsim.percar import FAIL_MARGIN, MarginScale


def _row(**values: float) -> np.ndarray:
    crit = default_criteria()
    nominal = {"1-1": 1, "1-2": 50, "1-3": 25, "1-4": 0.3, "2-1": 6, "2-2": 12, "2-3": 1,
               "2-4": 1, "3-1": 1, "3-2": 50, "4-1": 1.0}
    nominal.update({k.replace("_", "-"): v for k, v in values.items()})
    return np.array([[nominal[e] for e in crit.ids]], np.float64)


def test_a_margin_counts_in_its_sigmoids_slope():
    crit = default_criteria()
    scale = MarginScale.of(crit)
    j = {e: i for i, e in enumerate(crit.ids)}
    v = _row(**{"2_3": 3.0, "3_2": 46.0})
    m = scale.margins(v)[0]
    assert m[j["2-3"]] == 2.0 and m[j["3-2"]] == 1.0 and math.isnan(m[j["1-1"]])
    n = scale.normalized(v)[0]
    assert n[j["2-3"]] == 2.0 * crit.items["2-3"].sigmoid.c3
    assert n[j["3-2"]] == 1.0 * crit.items["3-2"].sigmoid.c1
    assert n[j["1-1"]] == math.inf  # a binary EC that passes bounds nothing
    assert scale.least(v)[0] == min(x for x in n if math.isfinite(x))
    # one σ of the station's uncertainty taken off every margin
    sigma = np.zeros(len(crit.ids))
    sigma[j["2-3"]] = 0.5
    assert scale.normalized(v, sigma)[0][j["2-3"]] == 1.5 * crit.items["2-3"].sigmoid.c3


def test_failing_unmeasured_and_disabled_ecs():
    crit = default_criteria()
    j = {e: i for i, e in enumerate(crit.ids)}
    v = _row(**{"1_1": 0.0, "2_3": 7.0})
    v[0, j["4-1"]] = np.nan
    scale = MarginScale.of(crit)
    n = scale.normalized(v)[0]
    assert n[j["1-1"]] == FAIL_MARGIN and n[j["4-1"]] == FAIL_MARGIN
    assert n[j["2-3"]] == -2.0 * crit.items["2-3"].sigmoid.c3 < 0
    assert not scale.passed(v)[0]
    off = dataclasses.replace(crit, items={**crit.items, "1-1": dataclasses.replace(
        crit.items["1-1"], enabled=False)})
    assert MarginScale.of(off).normalized(v)[0][j["1-1"]] == math.inf
