"""rvmsim.robust.stats: yield interval, margins, failure drivers."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.stats import binomtest

from rvmsim.robust import ec_margins, failure_drivers, wilson_interval, yield_estimate


@pytest.mark.parametrize("k,n", [(200, 200), (0, 10), (37, 64), (1, 3), (199, 200)])
def test_wilson_interval_is_scipys(k, n):
    ref = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    assert wilson_interval(k, n) == pytest.approx((ref.low, ref.high), abs=1e-9)


def test_yield_estimate_from_pass_flags():
    est = yield_estimate(np.array([True] * 9 + [False]))
    assert est.yield_ == 0.9 and est.n_pass == 9 and est.n == 10
    assert est.ci[0] < 0.9 < est.ci[1]
    assert yield_estimate(np.ones(200, bool)).ci[0] == pytest.approx(0.98115, abs=1e-4)


def test_margins_are_signed_distances_to_the_range():
    m = ec_margins(np.array([4.0, 6.0, 9.0, np.nan]), 4.0, 8.0)
    np.testing.assert_allclose(m[:3], [0.0, 2.0, -1.0])
    assert np.isnan(m[3])
    np.testing.assert_allclose(ec_margins(np.array([3.0]), None, 5.0), [2.0])
    assert np.isnan(ec_margins(np.array([1.0]), None, None)).all()


def test_failure_drivers_find_the_axis_and_its_pattern():
    rng = np.random.default_rng(0)
    yaw, roll, x = (rng.uniform(-1, 1, 300) for _ in range(3))
    failed = np.abs(roll) > 0.6  # symmetric in roll
    loads = np.array(["curb", "full"] * 150)
    effects = failure_drivers(failed, {"yaw_deg": yaw, "roll_deg": roll, "x_mm": x}, loads)
    top = effects[0]
    assert top.axis == "roll_deg"
    assert top.rates[1] < 0.05 and min(top.rates[0], top.rates[2]) > 0.5
    assert "low and high" in top.describe()
    monotone = failure_drivers(x > 0.5, {"yaw_deg": yaw, "x_mm": x})[0]
    assert monotone.axis == "x_mm" and "fails at high" in monotone.describe()
    by_load = failure_drivers(loads == "full", {"yaw_deg": yaw}, loads)[0]
    assert by_load.axis == "load" and by_load.rates == (0.0, 1.0)


def test_an_ec_failing_on_every_sample_has_no_driver():
    from rvmsim.robust import EcStats

    rng = np.random.default_rng(1)
    effects = tuple(failure_drivers(np.ones(90, bool), {"yaw_deg": rng.uniform(-1, 1, 90)}))
    all_fail = EcStats("2-1", "x", "%", 4.0, 8.0, True, 90, 1.0, 9.0, -1.0, 0, (), effects)
    assert effects[0].spread == 0 and all_fail.driver is None
    some = failure_drivers(np.arange(90) < 30, {"yaw_deg": np.arange(90.0)})
    ec = dataclasses.replace(all_fail, n_fail=30, drivers=tuple(some))
    assert ec.driver is not None and ec.driver.axis == "yaw_deg"
