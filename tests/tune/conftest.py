"""Fixtures of the tuning tests: a render cache of their own and one finished run."""

from __future__ import annotations

import os

import pytest

from rvmsim.tune import TuneRequest, tune
from rvmsim.search import TuningConfig
from rvmsim.runs import RunStore

from ..conftest import SCENES

CONFIG = {"tuned": ["zoom", "adv_v_shift", "adv_v_scale"], "output": {"size": [160, 90]},
          "top_m": 3, "batch": 20}


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """A render cache of this module's own (the runs below render vehicle A once)."""
    old = os.environ.get("RVMSIM_CACHE")
    os.environ["RVMSIM_CACHE"] = str(tmp_path_factory.mktemp("cache"))
    yield os.environ["RVMSIM_CACHE"]
    if old is None:
        os.environ.pop("RVMSIM_CACHE", None)
    else:
        os.environ["RVMSIM_CACHE"] = old


@pytest.fixture(scope="module")
def clean(cache, tmp_path_factory):
    """A finished random-search run of vehicle A (60 candidates, 3 batches)."""
    run = tmp_path_factory.mktemp("clean") / "run"
    tune(TuneRequest((SCENES / "vehicle_a.yaml",), "random", TuningConfig.model_validate(CONFIG),
                     seed=2, budget=60), run)
    return run


def top_of(run, m=3):
    """(idx, params, score) of the top-m trials, and the trial count."""
    store = RunStore(run / "run.sqlite")
    try:
        return [(r.idx, r.params, r.score) for r in store.top(m)], store.count()
    finally:
        store.close()
