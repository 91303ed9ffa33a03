"""The windowed candidate evaluator gives exactly the whole-image evaluation."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import EC_IDS, evaluate, load_criteria
from rvmsim.criteria import CandidateEvaluator
from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map

from .conftest import small_render

RANGES = {  # wide tuning ranges for the half-size sensors of the test renders
    "fov": (150.0, 210.0), "rad": (200.0, 450.0), "h_shift": (-40.0, 40.0),
    "v_shift": (-80.0, 80.0), "zoom": (0.25, 1.5), "adv_h_shift": (-0.4, 0.4),
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


@pytest.mark.parametrize("letter, angles", [("a", False), ("b", False), ("c", True)])
def test_windowed_equals_whole_image(letter, angles):
    img = small_render(letter)
    size = (img.camera.width, img.camera.height)
    out = OutputSpec(320, 240)
    ev = CandidateEvaluator(img.labels, out)
    differences = 0
    scored = 0
    for p in _candidates(60, seed=7, angles=angles):
        fast = ev(p)
        ref = evaluate(apply_map(img.labels, build_map(p, size, out)))
        for ec in EC_IDS:
            a, b = fast[ec].value, ref[ec].value
            differences += (a is None) != (b is None) or (a is not None and abs(a - b) > 1e-9)
        assert fast.score == pytest.approx(ref.score, rel=1e-9, abs=1e-300)
        scored += ref.score > 1e-6
    assert differences == 0
    # The sample is not all-degenerate: some candidates see the scene reasonably.
    assert sum(1 for p in _candidates(60, 7, angles) if ev(p)["4-1"].value is not None) > 10


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
    p = IspParams(fov=180, rad=300, zoom=0.5, adv_v_shift=0.2)
    r = CandidateEvaluator(img.labels, OutputSpec(320, 240), crit)(p)
    assert not r["4-1"].enabled and r.criteria_name == crit.name
    assert r.score == pytest.approx(np.prod([i.score for i in r.items if i.enabled]))
