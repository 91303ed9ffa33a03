"""rvmsim.robust.samples: Sobol draws of the variation, deterministic per seed."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from rvmsim.robust import (AxisDistribution, LoadState, Variation, draw_samples,
                           nominal_sample)


def _variation(levels: int = 2) -> Variation:
    return Variation(
        axes=(AxisDistribution("uniform", half_width=5.0), AxisDistribution("uniform", half_width=2.0),
              AxisDistribution(), AxisDistribution("uniform", half_width=1.0),
              AxisDistribution("normal", sigma=0.5, truncate=2.0), AxisDistribution()),
        load_states=(LoadState("curb", 0.0, 0.0, 0.3), LoadState("driver", -10.0, 0.2, 0.5),
                     LoadState("full", -50.0, 1.0, 0.2)),
        position_levels=levels)


def test_samples_are_deterministic_per_seed():
    a = draw_samples(_variation(), 50, seed=7)
    b = draw_samples(_variation(), 50, seed=7)
    c = draw_samples(_variation(), 50, seed=8)
    assert a == b
    assert [s.offsets for s in a] != [s.offsets for s in c]


def test_offsets_follow_their_distributions():
    s = draw_samples(_variation(), 256, seed=1)
    off = np.array([x.offsets for x in s])
    assert np.all(np.abs(off[:, 0]) <= 5.0) and np.abs(off[:, 0]).max() > 4.8
    assert np.all(off[:, 2] == 0.0) and np.all(off[:, 5] == 0.0)
    assert np.all(np.abs(off[:, 4]) <= 1.0)  # truncated at 2 σ
    # σ of a normal cut at ±2 σ: √(1 − 4 φ(2) / (Φ(2) − Φ(−2))) σ
    cut = np.sqrt(1 - 4 * norm.pdf(2.0) / (norm.cdf(2.0) - norm.cdf(-2.0)))
    assert abs(np.std(off[:, 4]) - 0.5 * cut) < 0.01
    # Sobol: the uniform axis is evenly covered (each eighth of the range holds 1/8)
    counts = np.histogram(off[:, 0], bins=8, range=(-5, 5))[0]
    assert counts.min() >= 30 and counts.max() <= 34
    shares = {n: sum(x.load.name == n for x in s) / 256 for n in ("curb", "driver", "full")}
    assert shares == pytest.approx({"curb": 0.3, "driver": 0.5, "full": 0.2}, abs=0.01)


def test_positions_are_rendered_at_a_few_levels():
    for levels, expect in ((2, {-2.5, 2.5}), (3, {-10 / 3, 0.0, 10 / 3})):
        s = draw_samples(_variation(levels), 64, seed=0)
        xs = {round(x.render_position_mm[0], 9) for x in s}
        assert xs == {round(v, 9) for v in expect}
        # the rendered level is the drawn value's bin: within half a bin
        assert all(abs(x.render_position_mm[0] - x.offsets[0]) <= 5.0 / levels + 1e-9 for x in s)
        assert all(x.render_position_mm[2] == 0.0 for x in s)


def test_scale_multiplies_the_tolerances():
    one = draw_samples(_variation(), 32, seed=2)
    two = draw_samples(_variation(), 32, seed=2, scale=2.0)
    np.testing.assert_allclose([t.offsets for t in two], 2 * np.array([o.offsets for o in one]))
    assert [t.load for t in two] == [o.load for o in one]  # loads do not scale
    assert all(t.scale == 2.0 for t in two)


def test_bad_requests_and_the_nominal_sample():
    with pytest.raises(ValueError, match="at least one sample"):
        draw_samples(_variation(), 0, seed=0)
    with pytest.raises(ValueError, match="tolerance scale"):
        draw_samples(_variation(), 4, seed=0, scale=float("nan"))
    nom = nominal_sample(_variation())
    assert nom.offsets == (0.0,) * 6 and nom.load.name == "curb"


def test_viewpoint_groups_hold_one_rendered_position_and_load_each():
    from rvmsim.robust import viewpoint_groups

    s = draw_samples(_variation(2), 128, seed=0)
    groups = viewpoint_groups(s)
    assert len(groups) == 2 * 2 * 3  # x and y at 2 levels, z fixed, 3 load states
    assert sorted(i for g in groups for i in g) == list(range(128))
    for g in groups:
        assert len({(s[i].render_position_mm, s[i].load) for i in g}) == 1



def test_fewer_position_levels_below_1x_keep_the_snapping_error():
    from rvmsim.robust import position_levels_at

    assert [position_levels_at(2, s) for s in (0.25, 0.5, 0.75, 1.0, 1.5, 2.0)] == [1, 1, 2, 2, 2, 2]
    assert [position_levels_at(3, s) for s in (0.3, 0.5, 1.0, 2.0)] == [1, 2, 3, 3]
    errors = {}
    for scale in (0.5, 1.0):
        samples = draw_samples(_variation(2), 256, seed=3, scale=scale)
        x = np.array([s.offsets[0] for s in samples])
        rx = np.array([s.render_position_mm[0] for s in samples])
        assert len(set(rx.round(9))) == (1 if scale == 0.5 else 2)
        errors[scale] = x - rx
    # x is ±5 mm uniform: at 1x two bins (rendered at ±2.5), at 0.5x one (at 0): the same
    # error, uniform in ±2.5 mm (RMS 5/(2·√3) = 1.443 mm)
    for e in errors.values():
        assert np.abs(e).max() <= 2.5 + 1e-9
        assert np.sqrt(np.mean(e ** 2)) == pytest.approx(5 / (2 * np.sqrt(3)), rel=0.03)
