"""Verdicts at the RVM image of record, whatever size the search measures at.

The reference is the full path (what ``rvmsim evaluate`` measures) at the size of record.  A
search at a smaller size converts its pixel-unit values and measures again at the size of
record whatever could pass; so a candidate passes in a run exactly when it passes on the
display — checked on the diverse top-M of real searches of all six bundled vehicles, at the
default search size (the size of record) and at a quarter of it.
"""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import (NEAR_SCORE, could_pass, criteria_from_text, default_criteria,
                             pixel_scales, record_size, score_batch, to_record_units)
from rvmsim.isp import OutputSpec
from rvmsim.pipeline import (ImagesEvaluator, RecordEvaluator, RecordRule, make_evaluator,
                             record_output)
from rvmsim.robust import AxisDistribution, SampleSet, Variation, draw_samples
from rvmsim.runs import RunSettings, RunStore, store_candidates
from rvmsim.scene import Display
from rvmsim.tune import Member, SearchSettings, search_scene
from rvmsim.search import TuningConfig, default_space

from ..conftest import bundled_scene, sensor_render, small_render

LETTERS = "abcdef"
RECORD = OutputSpec(1280, 720)
QUARTER_SEARCH = OutputSpec(320, 180)


def _full_at_record(images, crit):
    return make_evaluator(images, RECORD, crit, path="full", record=RECORD)


def test_the_size_of_record_comes_from_the_scene_else_the_criteria_else_1280x720():
    crit = default_criteria()
    assert record_size(crit) == (1280, 720)
    own = criteria_from_text("display: {rvm_image_px: [800, 450]}")
    assert record_size(own) == (800, 450)
    scene = bundled_scene("a")
    assert scene.display is None  # the bundled scene sets no display: the criteria's
    assert record_size(own, scene) == (800, 450)
    with_display = scene.model_copy(update={"display": Display(rvm_image_px=(960, 540))})
    assert record_size(own, with_display) == (960, 540)
    assert record_output(own, with_display, mirror=False) == OutputSpec(960, 540, False)


def test_pixel_values_scale_along_their_own_axis():
    crit = default_criteria()
    ids = list(crit.ids)
    s = pixel_scales(crit, (640, 480), (1280, 720))
    assert s[ids.index("3-1")] == 2.0  # a column offset: widths
    assert s[ids.index("2-3")] == 1.5  # a difference of heights: heights
    others = [k for k, ec in enumerate(crit.ecs) if ec.unit != "px"]
    assert np.all(s[others] == 1.0)
    v = np.arange(len(ids), dtype=float)
    v[0] = np.nan
    out = to_record_units(v, crit, (640, 480), (1280, 720))
    assert np.isnan(out[0]) and out[ids.index("3-1")] == 2 * ids.index("3-1")


def test_a_limit_in_px_is_twice_as_strict_at_half_the_size():
    """3-1 at 3 px of a 640 × 360 image is 6 px of record: a fail against ≤ 5 px, near."""
    crit = default_criteria()
    ids = list(crit.ids)
    v = np.full(len(ids), np.nan)
    v[ids.index("3-1")] = 3.0
    rec = to_record_units(v[None, :], crit, (640, 360), (1280, 720))
    b = score_batch(rec, crit)
    k = ids.index("3-1")
    assert rec[0, k] == 6.0 and not b.passed[0, k] and b.scores[0, k] >= NEAR_SCORE


@pytest.mark.parametrize("letter", LETTERS)
def test_a_smaller_search_is_judged_at_the_size_of_record(letter):
    """RecordEvaluator against the full path at 1280 × 720: the same verdict for every
    candidate; the same values for every one that could pass.  On the vehicle's own sensor,
    as in production (a test-scale fisheye upsampled 4× to the display of record shows
    objects that its 320 × 180 px search cannot)."""
    images = sensor_render(letter)
    crit = default_criteria()
    ev = make_evaluator(images, QUARTER_SEARCH, crit)
    assert isinstance(ev, RecordEvaluator)
    ref = _full_at_record(images, crit)
    space = default_space(images.camera)
    rng = np.random.default_rng(ord(letter))
    init = np.array([r.init for r in space.ranges])
    xs = np.clip(init + rng.uniform(-1, 1, (20, len(init))) * space.step, space.low, space.high)
    params = [space.params(x) for x in xs]
    verdicts = []
    for p in params:
        got, want = ev(p), ref(p)
        assert got.passed == want.passed, p
        verdicts.append(want.passed)
        if got.passed:
            assert got.as_dict()["ecs"] == want.as_dict()["ecs"]
        # what the search measures, the display shows (the search may miss a thin object
        # that the display of record shows: such a candidate fails, as above, either way)
        assert not np.any(np.isnan(ref.values(p)) & ~np.isnan(ev.values(p)))
    assert any(verdicts) or not all(verdicts)  # informative either way; the top-M test below


def _search(images, crit, config, budget=240):
    store = RunStore(":memory:")
    settings = SearchSettings(config, crit, "cmaes-solved", seed=100, budget=budget)
    search_scene(images, settings, store)
    return store


@pytest.mark.parametrize("search", ["record", "quarter"])
@pytest.mark.parametrize("letter", LETTERS)
def test_the_diverse_top_m_passes_on_the_display_exactly_when_the_run_says(letter, search):
    images = small_render(letter)
    crit = default_criteria()
    size = None if search == "record" else [QUARTER_SEARCH.width, QUARTER_SEARCH.height]
    config = TuningConfig.model_validate({"output": {"size": size}} if size else {})
    config = config.at_record(record_size(crit, images.scene))
    store = _search(images, crit, config)
    settings = RunSettings(scene="x", scene_key=None, vehicle=letter, strategy="cmaes-solved",
                           seed=100, budget=240, criteria_file=None, config=config,
                           judged_at=(RECORD.width, RECORD.height))
    store.begin(settings, config.space(images.camera), None)
    ref = _full_at_record(images, crit)
    pairs = store_candidates(store, settings, m=10, criteria=crit)
    assert pairs
    for cand, rec in pairs:
        assert bool(rec.passed) == ref(rec.params).passed, (cand.rank, rec.params)


def test_a_batch_of_images_is_judged_at_the_size_of_record():
    scene = bundled_scene("a")
    turn = AxisDistribution("uniform", half_width=1.0)
    samples = draw_samples(Variation(axes=(AxisDistribution(),) * 3 + (turn,) * 3), 12, seed=3)
    images = SampleSet.of(scene, samples, scale=0.25)
    crit = default_criteria()
    space = default_space(images.camera)
    params = space.params([r.init for r in space.ranges])
    fast = make_evaluator(images, QUARTER_SEARCH, crit)
    ref = make_evaluator(images, RECORD, crit, path="full", record=RECORD)
    assert fast.record_output.width == 1280
    a, b = fast(params), ref(params)
    assert np.array_equal(a.all_passed, b.all_passed)
    near = a.all_passed
    assert np.array_equal(a.values[near], b.values[near])


def test_one_rule_converts_and_sends_near_candidates_to_the_size_of_record():
    """RecordRule: values in units of record (pixel ECs scaled, others as measured) and the
    rows that could pass sent to the size of record; none at the size of record itself."""
    crit = default_criteria()
    rule = RecordRule(crit, (320, 180), (1280, 720))
    images = small_render("a")
    ev = make_evaluator(images, QUARTER_SEARCH, crit, record=QUARTER_SEARCH)
    space = default_space(images.camera)
    rng = np.random.default_rng(3)
    rows = np.array([ev.values(space.params(space.low + rng.random(len(space.low))
                                             * (space.high - space.low))) for _ in range(12)])
    values, undecided = rule.judge(rows)
    scales = pixel_scales(crit, (320, 180), (1280, 720))
    np.testing.assert_array_equal(values, rows * scales)
    np.testing.assert_array_equal(undecided, could_pass(score_batch(values, crit)))
    same = RecordRule(crit, (1280, 720), (1280, 720))
    assert same.at_record and not same.judge(rows)[1].any()
    # the evaluator measuring at a search size judges by the same rule
    rec = make_evaluator(images, QUARTER_SEARCH, crit, record=RECORD)
    for row, near in zip(rows, undecided):
        decided = rec.decided_values(row)
        assert (decided is None) == bool(near)


def test_make_evaluator_judges_a_runs_members_each_by_its_own_criteria():
    """A sequence of members → one evaluator giving each member's values as its own
    evaluator does, with a member's own criteria where it has them."""
    a, b = small_render("a"), small_render("b")
    own = criteria_from_text("name: own\necs: ['3-2']\n")
    members = [Member("a", a.labels, a.camera, a.scene),
               Member("b", b.labels, b.camera, b.scene, None, own)]
    evs = make_evaluator(members, QUARTER_SEARCH, default_criteria(), record=RECORD)
    assert isinstance(evs, ImagesEvaluator) and len(evs) == 2
    assert evs.evaluators[1].criteria.ids == own.ids != default_criteria().ids
    space = default_space(a.camera)
    for x in (space.low, space.high, (space.low + space.high) / 2):
        p = space.params(x)
        got = evs.values(p)
        want = [make_evaluator(a, QUARTER_SEARCH, default_criteria(), record=RECORD).values(p),
                make_evaluator(b, QUARTER_SEARCH, own, record=RECORD).values(p)]
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)
