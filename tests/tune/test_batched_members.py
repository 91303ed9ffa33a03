"""A robust run's candidates judged on every member with one map (pipeline.CandidateBatch,
pipeline.ImagesEvaluator, the members' sub-solves in one mapping): the same verdicts, value
for value, as judging each member on its own (real renders of a small scene and its
variation samples)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from rvmsim.criteria import default_criteria
from rvmsim.pipeline import CandidateBatch, CandidateEvaluator
from rvmsim.pipeline import RecordEvaluator
from rvmsim.render import cached_render
from rvmsim.robust import draw_samples, sample_images, variation_from_scene
from rvmsim.runs import RunStore
from rvmsim.scene import load_scene
from rvmsim.tune import Member, SearchSettings, members_scorer, score_params, search_scene
from rvmsim.search import TuningConfig, make_strategy

from .test_robust import small  # noqa: F401 - the fixture (a small scene, its own cache)


@pytest.fixture(scope="module")
def members(small):  # noqa: F811 - the fixture above
    """The small scene's nominal image and three variation samples, as a robust run's
    members, and the scene's own render."""
    scene = load_scene(small)
    images, _ = cached_render(scene)
    samples = draw_samples(variation_from_scene(scene), 3, 1)
    out = [Member("nominal", images.labels, images.camera, scene)]
    out += [Member(f"sample {i + 1}", im.labels, im.camera, scene)
            for i, im in enumerate(sample_images(scene, samples, color=False))]
    return out, images


@pytest.fixture(scope="module")
def candidates(members):
    """A short nominal search's best candidates (passing and near-passing ones) and its
    first ones, then uniform draws from its space: parameter sets."""
    _, images = members
    config = TuningConfig.model_validate({"output": {"size": [160, 90]}, "batch": 12})
    store = RunStore(":memory:")
    try:
        out = search_scene(images, SearchSettings(config, default_criteria(), "cmaes-solved",
                                                  2, 200), store)
        ps = [r.params for r in store.top(8) + store.trials(0, 8)]
    finally:
        store.close()
    space, rng = out.space, np.random.default_rng(4)
    return ps + [space.params(space.low + rng.random(len(space.low)) * (space.high - space.low))
                 for _ in range(8)]


@pytest.mark.parametrize("size", [(320, 180), (160, 90)], ids=["at-record", "search-size"])
def test_batched_members_give_each_members_own_verdicts(members, candidates, size):
    mem, images = members
    config = TuningConfig.model_validate({"output": {"size": list(size)}, "batch": 12})
    settings = SearchSettings(config, default_criteria(), "cmaes-solved", 2,
                              aggregate="quantile 0.25")
    strat = make_strategy("cmaes-solved", config.space(images.camera), config, 2)
    xs = [strat.space.vector(p) for p in candidates]
    scorer = members_scorer(mem, strat, settings)
    kind = RecordEvaluator if size == (160, 90) else CandidateEvaluator
    assert all(isinstance(ev, kind) for ev in scorer.evaluators)
    got = scorer(xs)
    # the reference: every member solved and judged on its own, one by one
    solvers = scorer.solver.solvers
    want, ps = [], []
    for x in xs:
        p = strat.space.params(x)
        solved = [s(p) for s in solvers]
        p = p.replace(**{n: float(np.mean([getattr(q, n) for s, q in zip(solvers, solved)
                                            if n in s.names]))
                         for n in scorer.solver.names})
        ps.append(p)
        per = [score_params(ev, [p]) for ev in scorer.evaluators]
        want.append([(float(m.score[0]), bool(m.passed[0]), m.ec_json[0]) for m in per])
    assert [[(s, ok, ec) for s, _, ok, ec in row] for row in got.members] == want
    if kind is RecordEvaluator:  # some members were measured again at the size of record
        assert any(ev.decided_values(ev.search.values(p)) is None
                   for p in ps for ev in scorer.evaluators)
    # in a worker process (pickled) the same
    assert pickle.loads(pickle.dumps(scorer))(xs).members == got.members


def test_a_batch_of_some_members_measures_those_members(members):
    mem, _ = members
    config = TuningConfig.model_validate({"output": {"size": [320, 180]}})
    evs = [CandidateEvaluator(m.labels, config.output_spec(), default_criteria(),
                              scene=m.scene, camera=m.camera) for m in mem]
    batch = CandidateBatch(evs)
    space = config.space(mem[0].camera)
    p = space.params((space.low + space.high) / 2.0)
    every = batch.values(p)
    assert [v.tolist() for v in batch.values(p, [3, 1])] == [every[3].tolist(),
                                                               every[1].tolist()]
    for ev, v in zip(evs, every):
        np.testing.assert_array_equal(ev.values(p), v)
    with pytest.raises(ValueError, match="one fisheye size"):
        CandidateBatch([evs[0], CandidateEvaluator(mem[0].labels[:-2], config.output_spec())])


def test_a_batch_of_many_members_measures_each_as_its_own_evaluator(members, candidates):
    """Eight members (the label images as the channels of one remap, past the four OpenCV
    fills with the border value) and members with other ECs (their own windows, each
    image measured on its own): measurements equal to each member's own evaluator, value
    and detail, on views that reach past the fisheye image."""
    from rvmsim.criteria import criteria_from_text
    from rvmsim.isp import IspParams, build_map

    mem, _ = members
    config = TuningConfig.model_validate({"output": {"size": [320, 180]}})
    out, space = config.output_spec(), config.space(mem[0].camera)
    assert space.ranges[1].name == "rad"
    fewer = criteria_from_text("ecs: [1-3, 2-1, 3-2, 4-1]\n")
    wide = IspParams(fov=210.0, rad=float(space.high[1]), zoom=0.25, adv_h_scale=0.5,
                     adv_v_scale=0.6)  # the widest view of the space
    for crits in ([default_criteria()] * 8, [default_criteria(), fewer] * 4):
        evs = [CandidateEvaluator(m.labels, out, c, scene=m.scene, camera=m.camera)
               for m, c in zip(mem * 2, crits)]
        batch = CandidateBatch(evs)
        for p in [*candidates, wide]:
            got = batch.measure(p)
            for ev, g in zip(evs, got):
                want = ev.measure(p)
                assert (g.values, g.details) == (want.values, want.details)
    # the wide view's bumper columns (at the image's edges) read outside the fisheye image
    xy = build_map(wide, (mem[0].labels.shape[1], mem[0].labels.shape[0]), out).xy
    edge = xy[:, :4]
    assert ((edge < -0.5) | (edge > np.array(mem[0].labels.shape[::-1]) - 0.5)).any()
