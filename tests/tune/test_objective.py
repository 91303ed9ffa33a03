"""The objective: score_vectors scores candidates as the evaluation path does, and stores
every EC's outcome in the criteria's order."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rvmsim.criteria import criteria_from_text
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import OutputSpec
from rvmsim.pipeline import evaluate_params
from rvmsim.tune import OBJECTIVE_FLOOR, score_vectors
from rvmsim.search import default_space
from rvmsim.runs import ecs_from_json

from ..conftest import small_render


def test_score_vectors_agrees_with_the_evaluation_path():
    images = small_render("a")
    criteria = criteria_from_text("criteria:\n  4-1: {enabled: false}\n")
    out = OutputSpec(320, 180)
    ev = CandidateEvaluator(images.labels, out, criteria)
    space = default_space(images.camera, ("fov", "rad", "zoom", "adv_v_shift"))
    rng = np.random.default_rng(4)
    xs = [np.array([r.init for r in space.ranges])] + list(rng.uniform(space.low, space.high,
                                                                       size=(5, 4)))
    b = score_vectors(ev, space, xs)
    assert len(b.score) == len(b.objective) == len(b.passed) == len(b.ec_json) == 6
    for k, x in enumerate(xs):
        p = space.params(x)
        assert json.loads(b.params_json[k]) == {n: getattr(p, n) for n in p.names()}
        ref = evaluate_params(images, p, out, criteria, annotate=False).ec
        assert b.score[k] == pytest.approx(ref.score, abs=1e-12)
        assert b.passed[k] == ref.passed
        ecs = ecs_from_json(b.ec_json[k])
        assert list(ecs) == list(criteria.ids)
        for item in ref.items:
            o = ecs[item.id]
            assert o.passed == item.passed and o.score == pytest.approx(item.score, abs=1e-12)
            assert (o.value is None) == (item.value is None)
            if o.value is not None:
                assert o.value == pytest.approx(item.value)
        enabled = [i for i in ref.items if i.enabled]
        assert len(enabled) == 10
        assert b.objective[k] == pytest.approx(sum(math.log(max(i.score, OBJECTIVE_FLOOR))
                                                   for i in enabled))
