"""Scoring: the vectorised batch scores agree with each Criterion."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import EC_IDS, default_criteria, load_criteria, score_batch


def test_vectorised_scores_agree_with_each_criterion(tmp_path):
    """score_batch (what tuning stores) gives Criterion.score / passes for every EC, for
    measured and missing values, with the defaults and with a customer's file using
    tolerances, one-sided ranges and a switched-off EC."""
    f = tmp_path / "c.yaml"
    f.write_text("criteria:\n  2-1: {range: [3, 9], tolerance: 2}\n"
                 "  1-3: {range: [20, null], tolerance: 5}\n  4-1: {enabled: false}\n")
    rng = np.random.default_rng(3)
    for crit in (default_criteria(), load_criteria(f)):
        values = rng.uniform(-5, 60, size=(400, len(EC_IDS)))
        values[:, [0, 7]] = rng.integers(0, 2, size=(400, 2))  # the binary ECs
        values[rng.random(values.shape) < 0.1] = np.nan
        b = score_batch(values, crit)
        for i in range(len(values)):
            total, ok = 1.0, True
            for j, ec in enumerate(EC_IDS):
                c = crit.items[ec]
                v = None if np.isnan(values[i, j]) else float(values[i, j])
                # (np.tanh and math.tanh may differ in the last bit: 1e-15 absolute)
                assert b.scores[i, j] == pytest.approx(c.score(v), rel=1e-12, abs=1e-15)
                assert bool(b.passed[i, j]) == c.passes(v)
                if c.enabled:
                    total *= c.score(v)
                    ok &= c.passes(v)
            assert b.score[i] == pytest.approx(total, rel=1e-9, abs=1e-15)
            assert bool(b.all_passed[i]) == ok


