"""rvmsim.robust.sensitivity: an EC's value as a fitted formula of the offsets and load,
recovered from synthetic values of known formulas."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.robust import GOOD_R2, fit_sensitivity

STATES = ("curb", "driver", "full")


def _samples(n: int = 200, seed: int = 0) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Offsets as robustness draws them: ±1° uniform angles, positions at two rendered
    levels (±2.5 mm), three load states."""
    rng = np.random.default_rng(seed)
    axes = {a: rng.uniform(-1.0, 1.0, n) for a in ("yaw_deg", "pitch_deg", "roll_deg")}
    axes |= {a: rng.choice([-2.5, 2.5], n) for a in ("x_mm", "y_mm", "z_mm")}
    return axes, rng.choice(STATES, n, p=[0.3, 0.5, 0.2])


def _load_term(loads: np.ndarray, shifts: dict[str, float]) -> np.ndarray:
    return np.array([shifts.get(str(s), 0.0) for s in loads])


def test_a_linear_formula_with_load_states_is_recovered_through_noise():
    axes, loads = _samples()
    rng = np.random.default_rng(1)
    truth = {"pitch_deg": 1.3, "y_mm": -0.2, "roll_deg": 0.25}
    shifts = {"driver": 0.3, "full": 1.5}
    noise = 0.05
    v = (6.0 + sum(b * axes[a] for a, b in truth.items()) + _load_term(loads, shifts)
         + rng.normal(0.0, noise, loads.size))
    s = fit_sensitivity(v, axes, loads, states=STATES, ec_id="2-1", unit="%")
    assert s is not None and s.model == "linear" and s.good
    coef = dict(s.coefficients)
    assert set(coef) == {*truth, "load:driver", "load:full"}
    for a, b in truth.items():
        assert coef[a] == pytest.approx(b, abs=0.03)
    assert coef["load:driver"] == pytest.approx(0.3, abs=0.03)
    assert coef["load:full"] == pytest.approx(1.5, abs=0.03)
    assert s.intercept == pytest.approx(6.0, abs=0.03) and s.reference_load == "curb"
    assert s.rms == pytest.approx(noise, rel=0.2)
    assert {"yaw_deg", "x_mm", "z_mm"} <= set(s.dropped)
    text = s.describe()
    assert text.startswith(f"2-1 ≈ {s.intercept:.3g} + ") and "·pitch" in text
    assert "- 0.2" in text and "·y" in text and "·[full]" in text
    assert text.endswith(f"%, R² {s.r2:.2f}")


def test_the_absolute_value_of_a_sum_is_recovered():
    """2-3's form on vehicle A: |16.0·yaw + 16.5·roll| px, which a linear fit sees as
    flat (it is symmetric)."""
    axes, loads = _samples(seed=2)
    rng = np.random.default_rng(3)
    v = np.abs(16.0 * axes["yaw_deg"] + 16.5 * axes["roll_deg"]) + rng.normal(0, 0.6, loads.size)
    s = fit_sensitivity(v, axes, loads, states=STATES, ec_id="2-3", unit="px")
    assert s is not None and s.model == "abs" and s.good
    assert s.r2_linear < 0.3 < GOOD_R2 < s.r2
    coef = dict(s.coefficients)
    assert set(coef) == {"yaw_deg", "roll_deg"}
    assert coef["yaw_deg"] == pytest.approx(16.0, rel=0.03)
    assert coef["roll_deg"] == pytest.approx(16.5, rel=0.03)
    assert abs(s.intercept) < 0.5
    b = dict(s.coefficients)
    assert s.describe() == (f"2-3 ≈ |{b['roll_deg']:#.3g}·roll + {b['yaw_deg']:#.3g}·yaw| px, "
                            f"R² {s.r2:.2f}")


def test_an_absolute_value_with_an_offset_negative_terms_and_load_states():
    axes, loads = _samples(seed=4)
    rng = np.random.default_rng(5)
    inner = (-0.4 - 3.0 * axes["pitch_deg"] + 0.5 * axes["x_mm"]
             - _load_term(loads, {"driver": 0.9, "full": 2.4}))
    v = np.abs(inner) + rng.normal(0, 0.1, loads.size)
    s = fit_sensitivity(v, axes, loads, states=STATES, unit="px")
    assert s is not None and s.model == "abs" and s.good
    coef = dict(s.coefficients)
    # |z| = |−z|: shown with the largest term positive, so every sign turns
    assert coef["pitch_deg"] == pytest.approx(3.0, rel=0.05)
    assert coef["x_mm"] == pytest.approx(-0.5, rel=0.05)
    assert coef["load:driver"] == pytest.approx(0.9, abs=0.1)
    assert coef["load:full"] == pytest.approx(2.4, abs=0.1)
    assert s.intercept == pytest.approx(0.4, abs=0.1)


def test_a_positive_value_is_not_folded():
    """A linear value that stays positive is the abs model too; the linear one is kept."""
    axes, loads = _samples(seed=6)
    v = 20.0 + 2.0 * axes["yaw_deg"]
    s = fit_sensitivity(v, axes, loads)
    assert s is not None and s.model == "linear" and s.r2 == pytest.approx(1.0)
    assert dict(s.coefficients) == {"yaw_deg": pytest.approx(2.0)}


@pytest.mark.parametrize("kind", ["noise", "wiggle"])
def test_no_good_fit_says_so(kind):
    axes, loads = _samples(seed=7)
    rng = np.random.default_rng(8)
    v = (rng.normal(0.0, 1.0, loads.size) if kind == "noise"
         else np.sin(6 * axes["yaw_deg"]) * np.cos(5 * axes["roll_deg"]))
    s = fit_sensitivity(v, axes, loads, states=STATES, ec_id="1-1", unit="%")
    assert s is not None and s.r2 < 0.3 and not s.good
    assert s.describe() == (f"1-1: follows none of the mount offsets or the load (no linear "
                            f"or |linear| fit, R² {s.r2:.2f})")  # no formula of noise


def test_a_fit_that_explains_part_says_partly_with_its_formula():
    axes, loads = _samples(seed=7)
    rng = np.random.default_rng(8)
    v = 2.0 * axes["yaw_deg"] + rng.normal(0.0, 1.5 * axes["yaw_deg"].std(), loads.size)
    s = fit_sensitivity(v, axes, loads, states=STATES, ec_id="1-1", unit="%")
    assert s is not None and 0.5 <= s.r2 < 0.8 and not s.good, s.r2
    assert s.describe() == (f"1-1: only partly follows the mount offsets and load (R² "
                            f"{s.r2:.2f}: {s.formula()})")


def test_unmeasured_samples_are_left_out_and_too_few_give_none():
    axes, loads = _samples(seed=9)
    v = 1.0 + 0.5 * axes["roll_deg"]
    v[::3] = np.nan
    s = fit_sensitivity(v, axes, loads)
    assert s is not None and s.n == int(np.isfinite(v).sum())
    assert dict(s.coefficients) == {"roll_deg": pytest.approx(0.5)}
    assert fit_sensitivity(np.full(loads.size, np.nan), axes, loads) is None
    few = {a: x[:8] for a, x in axes.items()}
    assert fit_sensitivity(v[:8], few, loads[:8]) is None


def test_a_constant_value_has_no_terms():
    axes, loads = _samples(seed=10)
    s = fit_sensitivity(np.full(loads.size, 5.0), axes, loads, ec_id="1-4", unit="px")
    assert s is not None and s.coefficients == () and s.r2 == 1.0
    assert s.describe() == "1-4 = 5.00 px on every sample"
    d = s.as_dict()
    assert d["model"] == "linear" and d["coefficients"] == {} and d["good"]


def test_the_absolute_value_is_found_with_few_samples():
    """With fewer samples than the quadratic start has terms (30 for six axes and three
    load states), the starts from each axis and each sum or difference of two find it."""
    axes, loads = _samples(n=24, seed=11)
    rng = np.random.default_rng(12)
    v = np.abs(16.0 * axes["yaw_deg"] - 16.5 * axes["roll_deg"]) + rng.normal(0, 0.6, 24)
    s = fit_sensitivity(v, axes, loads, states=STATES, unit="px")
    assert s is not None and s.model == "abs" and s.good
    coef = dict(s.coefficients)
    assert set(coef) == {"yaw_deg", "roll_deg"}
    assert abs(coef["yaw_deg"]) == pytest.approx(16.0, rel=0.1)
    assert coef["roll_deg"] == pytest.approx(-16.5 * np.sign(coef["yaw_deg"]), rel=0.1)
