"""make_evaluator: the one factory of evaluators, and each fast path against the full path.

The full path is what ``rvmsim evaluate`` measures: the whole fisheye label image remapped
(:func:`rvmsim.isp.process`) and every EC measured on it.  Each fast path must give every EC
value exactly (all six bundled vehicles; the paper's criteria, fmvss111-full and custom ECs):

- one image, many candidates: the windowed path (tuning);
- a batch of images, one setting: the RVM-pixel path (variation samples: only the fisheye
  pixels the RVM image shows are re-folded).

Here every evaluator measures at its size of record (``record=OUT``): the paths themselves;
tests/pipeline/test_record.py checks the judging at another size of record.
"""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import default_criteria, load_criteria
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.isp import IspParams, OutputSpec
from rvmsim.pipeline import (EvaluationPath, FullEvaluator, SetEvaluator, evaluate_params,
                             make_evaluator)
from rvmsim.robust import AxisDistribution, SampleSet, Variation, draw_samples, sample_images
from rvmsim.search import default_space

from ..conftest import bundled_scene, small_render
from .custom_ecs import custom_criteria

LETTERS = "abcdef"
#: The paper's ECs, FMVSS 111's, and custom ones (more groups than one distance image holds,
#: an upper-region group, a fixed region, a plugin's EC).
CRITERIA = {"paper": default_criteria, "fmvss111-full": lambda: load_criteria("fmvss111-full"),
            "custom": custom_criteria}
OUT = OutputSpec(320, 180)


def _candidates(camera, n: int, seed: int) -> list[IspParams]:
    """Half spread over the whole tuning space fitted to ``camera``, half near its fitted
    initial values (where views are sensible and most ECs measure something)."""
    space = default_space(camera)
    rng = np.random.default_rng(seed)
    init = np.array([r.init for r in space.ranges])
    wide = rng.uniform(space.low, space.high, (n - n // 2, len(init)))
    near = np.clip(init + rng.uniform(-1, 1, (n // 2, len(init))) * space.step,
                   space.low, space.high)
    return [space.params(x) for x in np.vstack([wide, near])]


def _assert_same_values(fast: np.ndarray, full: np.ndarray, ids) -> None:
    """Equal EC for EC, NaN (not measured) in the same places."""
    assert fast.shape == full.shape
    for k, ec in enumerate(ids):
        a, b = fast[..., k], full[..., k]
        assert np.array_equal(np.isnan(a), np.isnan(b)), ec
        assert np.array_equal(a[~np.isnan(a)], b[~np.isnan(b)]), ec


@pytest.mark.parametrize("criteria", list(CRITERIA))
@pytest.mark.parametrize("letter", LETTERS)
def test_windowed_path_equals_the_full_path(letter, criteria):
    images = small_render(letter)
    crit = CRITERIA[criteria]()
    fast = make_evaluator(images, OUT, crit, record=OUT)
    full = make_evaluator(images, OUT, crit, path="full", record=OUT)
    assert isinstance(fast, CandidateEvaluator) and fast.windowed
    assert isinstance(full, FullEvaluator)
    params = _candidates(images.camera, 12, seed=ord(letter))
    a = np.array([fast.values(p) for p in params])
    b = np.array([full.values(p) for p in params])
    _assert_same_values(a, b, crit.ids)
    # not vacuous: most ECs are measured on some candidate, every candidate scores alike
    assert np.mean(np.isfinite(b).any(axis=0)) > 0.8
    for p in params[-3:]:
        assert fast(p).score == full(p).score
        assert full(p).as_dict() == evaluate_params(images, p, OUT, crit, annotate=False).ec.as_dict()


def _rotations_only() -> Variation:
    """±1.5° on each mount angle, nothing else: every sample is a re-fold of one cube."""
    turn = AxisDistribution("uniform", half_width=1.5)
    return Variation(axes=(AxisDistribution(),) * 3 + (turn,) * 3)


@pytest.mark.parametrize("letter", LETTERS)
def test_rvm_pixel_path_equals_the_full_path(letter):
    scene = bundled_scene(letter)
    samples = draw_samples(_rotations_only(), 6, seed=ord(letter))
    images = SampleSet.of(scene, samples, scale=0.25)
    crit = default_criteria()
    fast = make_evaluator(images, OUT, crit, record=OUT)
    full = make_evaluator(images, OUT, crit, path=EvaluationPath.FULL, record=OUT)
    assert isinstance(fast, SetEvaluator) and fast.path is EvaluationPath.RVM_PIXELS
    assert full.path is EvaluationPath.FULL
    space = default_space(images.camera)
    initial = space.params([r.init for r in space.ranges])
    for params in (initial, _candidates(images.camera, 2, seed=ord(letter))[1]):
        a, b = fast(params), full(params)
        _assert_same_values(a.values, b.values, crit.ids)
        assert np.array_equal(a.passed, b.passed) and np.array_equal(a.score, b.score)
        # and the full path is each sample's own fisheye image through evaluate_params
        for row, im in zip(b.values, sample_images(scene, samples, scale=0.25, color=False)):
            ec = evaluate_params(im, params, OUT, crit, annotate=False).ec
            ref = np.array([np.nan if ec[e].value is None else ec[e].value for e in crit.ids])
            _assert_same_values(row, ref, crit.ids)
    assert np.isfinite(a.values).mean() > 0.5


def test_criteria_that_read_the_scene_take_the_full_path_on_a_batch():
    scene = bundled_scene("a")
    samples = draw_samples(_rotations_only(), 3, seed=1)
    images = SampleSet.of(scene, samples, scale=0.25)
    crit = load_criteria("fmvss111-full")
    ev = make_evaluator(images, OUT, crit, record=OUT)
    assert ev.path is EvaluationPath.FULL
    with pytest.raises(ValueError, match="read the scene"):
        make_evaluator(images, OUT, crit, path="rvm-pixels", record=OUT)
    space = default_space(images.camera)
    params = space.params([r.init for r in space.ranges])
    got = ev(params)
    for row, im in zip(got.values, sample_images(scene, samples, scale=0.25, color=False)):
        ec = evaluate_params(im, params, OUT, crit, annotate=False).ec
        assert [None if np.isnan(v) else v for v in row] == [ec[e].value for e in crit.ids]
    assert np.isfinite(got.values[:, list(crit.ids).index("1-6")]).all()


def test_per_image_parameters_and_indices():
    """One setting per image (per-car values) is each image judged with its own setting."""
    scene = bundled_scene("a")
    samples = draw_samples(_rotations_only(), 4, seed=2)
    images = SampleSet.of(scene, samples, scale=0.25)
    ev = make_evaluator(images, OUT, record=OUT)
    space = default_space(images.camera)
    base = space.params([r.init for r in space.ranges])
    other = base.replace(adv_v_shift=base.adv_v_shift + 0.1)
    mixed = ev([base, other, base, other])
    alone = [ev(base, indices=[0, 2]), ev(other, indices=[1, 3])]
    _assert_same_values(mixed.values[[0, 2]], alone[0].values, ev.criteria.ids)
    _assert_same_values(mixed.values[[1, 3]], alone[1].values, ev.criteria.ids)
    assert not np.array_equal(mixed.values[0], mixed.values[1], equal_nan=True)
    with pytest.raises(ValueError, match="2 parameter sets for 4 images"):
        ev([base, other])


def test_the_factory_refuses_what_cannot_be_measured():
    images = small_render("a")
    crit = load_criteria("fmvss111-full")
    bare = type(images)(color=images.color, labels=images.labels, camera=images.camera)
    with pytest.raises(ValueError, match="1-5, 1-6, 6-1 read the scene"):
        make_evaluator(bare, OUT, crit, record=OUT)
    with pytest.raises(ValueError, match="windowed or the full path"):
        make_evaluator(images, OUT, crit, path="rvm-pixels", record=OUT)
    with pytest.raises(ValueError):
        make_evaluator(images, OUT, crit, path="fastest", record=OUT)
    # the paper's criteria need no scene
    assert isinstance(make_evaluator(bare, OUT, record=OUT), CandidateEvaluator)
