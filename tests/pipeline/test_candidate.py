"""The windowed candidate evaluator (rvmsim/pipeline/candidate.py): its windows, its criteria
and its failures.  That it gives exactly the whole-image evaluation, for the paper's, FMVSS
111's and custom ECs, is the contract test in test_evaluators.py."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import (Criteria, EcDefinition, EcFailedError, Measurement,
                             default_criteria, evaluate, load_criteria)
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map

from ..conftest import small_render
from .custom_ecs import SKY_UP, custom_criteria

RANGES = {  # wide tuning ranges for the test scale's 320 × 240 px sensors
    "fov": (150.0, 210.0), "rad": (100.0, 225.0), "h_shift": (-20.0, 20.0),
    "v_shift": (-40.0, 40.0), "zoom": (0.25, 1.5), "adv_h_shift": (-0.4, 0.4),
    "adv_v_shift": (-0.8, 0.8), "adv_h_scale": (0.5, 2.0), "adv_v_scale": (0.5, 2.0),
}


def _candidates(n: int, seed: int, angles: bool = False) -> list[IspParams]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        kw = {k: rng.uniform(*r) for k, r in RANGES.items()}
        if angles:
            kw.update(h_pan=rng.uniform(0, 30), v_pan=rng.uniform(-180, 180),
                      tilt=rng.uniform(-20, 20), theta=rng.uniform(0, 20), phi=rng.uniform(-180, 180))
        out.append(IspParams(**kw))
    return out


def test_windows_are_small_for_a_typical_view():
    img = small_render("a")
    cam = img.camera
    out = OutputSpec(320, 240)
    ev = CandidateEvaluator(img.labels, out)
    p = IspParams(fov=180, rad=cam.fx * np.pi / 2, zoom=0.7, adv_v_shift=0.2)
    wins = ev.windows(p)
    area = {k: (x1 - x0) * (y1 - y0) for k, (x0, y0, x1, y1) in wins.items()}
    assert area["board"] < 0.2 * out.width * out.height
    assert area["guide2"] < 0.2 * out.width * out.height
    assert area["upper_body"] == 0  # no garnish/trunk can reach the top half here


def test_uses_the_given_criteria(tmp_path):
    img = small_render("a")
    crit_file = tmp_path / "c.yaml"
    crit_file.write_text("criteria:\n  4-1: {enabled: false}\n  2-4: {enabled: false}\n")
    crit = load_criteria(crit_file)
    p = IspParams(fov=180, rad=150, zoom=0.5, adv_v_shift=0.2)
    r = CandidateEvaluator(img.labels, OutputSpec(320, 240), crit)(p)
    assert not r["4-1"].enabled and r.criteria_name == crit.name
    assert r.score == pytest.approx(np.prod([i.score for i in r.items if i.enabled]))


def test_a_group_of_the_upper_region_is_read_in_its_rows_only():
    """A custom group declared for the upper region (sky_up) gets a window inside the rows
    the options give the upper region."""
    img = small_render("a")
    crit = custom_criteria()
    ev = CandidateEvaluator(img.labels, OutputSpec(320, 240), crit)
    wins = ev.windows(_candidates(1, seed=5)[0])
    assert wins["sky_up"][3] <= crit.options.upper_rows(240)


def test_an_undeclared_group_fails_in_both_paths():
    img = small_render("a")
    sneaky = EcDefinition("sneaky", "sneaky", "", (), lambda s, o: Measurement(s.window(SKY_UP)[0]))
    base = default_criteria()
    crit = Criteria("x", {**base.items, "sneaky": sneaky.default_criterion()}, ecs=base.ecs + (sneaky,))
    p = IspParams(fov=180, rad=150, zoom=0.5, adv_v_shift=0.2)
    out = OutputSpec(160, 120)
    # an EC outside rvmsim's own plugins: its failure is one line naming it (EcFailedError)
    with pytest.raises(EcFailedError, match="EC sneaky: .*KeyError: .*not declared"):
        CandidateEvaluator(img.labels, out, crit).values(p)
    with pytest.raises(EcFailedError, match="EC sneaky: .*KeyError: .*not declared"):
        evaluate(apply_map(img.labels, build_map(p, (img.camera.width, img.camera.height), out)), crit)


def test_a_selection_without_label_groups(tmp_path):
    """Criteria whose ECs read only fixed regions (the bumper columns): no distance image."""
    img = small_render("b")
    size = (img.camera.width, img.camera.height)
    f = tmp_path / "c.yaml"
    f.write_text("ecs: [2-3, 2-1]\nedge_columns: 6\n")
    crit = load_criteria(f)
    out = OutputSpec(200, 150)
    ev = CandidateEvaluator(img.labels, out, crit)
    assert crit.groups == () and ev.windows(_candidates(1, 3)[0]) == {}
    for p in _candidates(15, seed=3):
        ref = evaluate(apply_map(img.labels, build_map(p, size, out)), crit)
        assert ev.values(p).tolist() == [ref["2-3"].value, ref["2-1"].value]
