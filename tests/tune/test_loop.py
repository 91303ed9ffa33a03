"""The search loop: worker chunks, and the reusable core a sweep point or a task calls."""

from __future__ import annotations

import dataclasses

import pytest


def test_batches_split_into_shrinking_chunks_that_cover_them():
    """Worker chunks (guided self-scheduling) partition the batch in order and shrink, so
    the last ones are small."""
    from rvmsim.tune.loop import _chunks

    for n, workers in ((1024, 2), (1000, 3), (10, 2), (1, 4)):
        c = _chunks(n, workers)
        assert c[0][0] == 0 and c[-1][1] == n
        assert all(a[1] == b[0] for a, b in zip(c, c[1:]))
        sizes = [b - a for a, b in c]
        assert sizes == sorted(sizes, reverse=True) and sizes[-1] <= 8
    assert _chunks(0, 2) == []


def _problem():
    from rvmsim.criteria import default_criteria
    from rvmsim.search import TuningConfig

    from ..conftest import small_render

    images = small_render("a")
    config = TuningConfig.model_validate({"tuned": ["fov", "zoom", "adv_v_shift",
                                                    "adv_v_scale"],
                                          "output": {"size": [160, 90]}, "batch": 16})
    return images, config, default_criteria()


def test_search_scene_is_the_loop_over_the_config_strategy_and_evaluator():
    """search_scene = make_strategy + run_search with score_vectors, on one process or two."""
    from rvmsim.pipeline import CandidateEvaluator
    from rvmsim.tune import SearchOptions, SearchSettings, run_search, score_vectors, search_scene
    from rvmsim.search import make_strategy
    from rvmsim.runs import RunStore, StopReason

    images, config, criteria = _problem()
    space = config.space(images.camera)
    strat = make_strategy("random", space, config, 3, budget=40)
    ev = CandidateEvaluator(images.labels, config.output_spec(), criteria)
    by_hand = RunStore(":memory:")
    run_search(strat, lambda xs: score_vectors(ev, space, xs), by_hand)
    for workers in (1, 2):
        store = RunStore(":memory:")
        out = search_scene(images, SearchSettings(config, criteria, "random", 3, 40), store,
                           options=SearchOptions(workers=workers))
        assert (out.evaluated, out.replayed, out.stopped, out.total) == (40, 0,
                                                                           StopReason.DONE, 40)
        assert out.space == space
        assert store.trials() == by_hand.trials()
        assert out.best == by_hand.top(1)[0]
        store.close()
    by_hand.close()


def test_search_scene_continues_its_store_and_refuses_other_settings():
    """A search stopped by max_time continues in the same store to the unbroken result; a
    store of other settings is not mixed in."""
    from rvmsim.errors import RvmsimError
    from rvmsim.tune import SearchOptions, SearchSettings, search_scene
    from rvmsim.runs import RunStore, StopReason

    images, config, criteria = _problem()
    how = SearchSettings(config, criteria, "cmaes", seed=1, budget=60)
    whole = RunStore(":memory:")
    search_scene(images, how, whole)
    store = RunStore(":memory:")
    first = search_scene(images, how, store, options=SearchOptions(max_time=0.0))
    assert first.stopped is StopReason.MAX_TIME and 0 < first.evaluated < 60
    rest = search_scene(images, how, store)
    assert rest.replayed == first.evaluated and rest.stopped is StopReason.DONE
    assert store.trials() == whole.trials()
    with pytest.raises(RvmsimError, match="trial 0 differs from what this strategy, seed"):
        search_scene(images, dataclasses.replace(how, seed=2), store)
