"""The bidirectional sigmoid of the paper's equation (4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rvmsim.criteria import Sigmoid


def test_sigmoid_shape():
    s = Sigmoid(c1=3, c2=4, c3=3, c4=8)
    inside = [s(x) for x in np.linspace(5, 7, 9)]
    assert min(inside) > 0.95
    below = [s(x) for x in np.linspace(-5, 4, 50)]
    above = [s(x) for x in np.linspace(8, 20, 50)]
    assert np.all(np.diff(below) > 0) and np.all(np.diff(above) < 0)
    assert s(4) == pytest.approx(0.5, abs=1e-3) and s(8) == pytest.approx(0.5, abs=1e-3)
    assert s(-1e6) == 0.0 and s(1e6) == 0.0  # no overflow, no NaN


def test_one_threshold_forms():
    larger = Sigmoid(c1=0.5, c2=10)  # c4 = +inf
    smaller = Sigmoid(c2=-math.inf, c3=1.17, c4=5)
    assert larger(1e9) == pytest.approx(1.0) and larger(10) == pytest.approx(0.5)
    assert np.all(np.diff([larger(x) for x in range(0, 40)]) > 0)
    assert smaller(-1e9) == pytest.approx(1.0) and smaller(5) == pytest.approx(0.5)
    assert np.all(np.diff([smaller(x) for x in range(0, 20)]) < 0)
    with pytest.raises(ValueError):
        Sigmoid(c2=5, c4=1)


def test_automatic_coefficients_from_range_and_tolerance():
    s = Sigmoid.from_range(4.0, 8.0, tolerance=1.0)
    assert s(4.0) == pytest.approx(0.95, abs=0.005) and s(8.0) == pytest.approx(0.95, abs=0.005)
    assert s(3.0) == pytest.approx(0.05, abs=0.005) and s(9.0) == pytest.approx(0.05, abs=0.005)
    assert s(6.0) > 0.99
    one = Sigmoid.from_range(15.0, None, tolerance=4.0)
    assert one(15) == pytest.approx(0.95) and one(11) == pytest.approx(0.05) and one(1e6) == 1.0


