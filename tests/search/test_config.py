"""The tuning config: validation with one-line errors naming the key, the strategy sections
the registry names, and the strategies it sets up."""

from __future__ import annotations

import pytest

from rvmsim.errors import RvmsimError, TuningConfigError
from rvmsim.search import (
    STRATEGIES,
    CmaEs,
    CmaEsSolved,
    GridToRandom,
    RandomSearch,
    TuningConfig,
    load_tuning_config,
    make_strategy,
)

from ..conftest import small_render


def _space():
    return TuningConfig(tuned=["zoom", "adv_v_shift"]).space(small_render("a").camera)


def test_every_registered_strategy_has_its_config_section():
    assert list(STRATEGIES) == ["grid-random", "cmaes", "cmaes-solved", "random"]
    for name, cls in STRATEGIES.items():
        assert cls.name == name and cls.summary
        field = TuningConfig.model_fields[cls.section]
        assert field.annotation is cls.Settings
        assert isinstance(TuningConfig().strategy_settings(name), cls.Settings)
        assert isinstance(make_strategy(name, _space(), TuningConfig(), 0), cls)


def test_a_setting_the_strategy_does_not_use_is_rejected(tmp_path):
    """`random.sigma0` was accepted and ignored: the random strategy has no step size."""
    path = tmp_path / "t.yaml"
    path.write_text("batch: 64\nrandom:\n  budget: 500\n  sigma0: 0.2\n")
    with pytest.raises(TuningConfigError) as err:
        load_tuning_config(path)
    e = err.value
    assert (e.file, e.key, e.line) == (str(path), "random.sigma0", 4)
    assert "not a setting of the random strategy (its settings: budget)" in str(e)
    assert "\n" not in str(e)
    path.write_text("cmaes: {sigma0: 0.2, popsize: 8}\n")
    with pytest.raises(TuningConfigError, match=r"cmaes\.popsize: not a setting of the cmaes "
                                                r"strategy \(its settings: budget, sigma0\)"):
        load_tuning_config(path)
    # Other errors keep their messages.
    path.write_text("random: {budget: 0}\n")
    with pytest.raises(TuningConfigError, match=r"random\.budget: .*greater than or equal"):
        load_tuning_config(path)
    path.write_text("bogus: 1\n")
    with pytest.raises(TuningConfigError, match="bogus: unknown key"):
        load_tuning_config(path)


def test_sections_set_up_their_strategies(tmp_path):
    path = tmp_path / "t.yaml"
    path.write_text("batch: 32\ngrid_random: {top_n: 3, trials: 50}\ncmaes: {budget: 90, "
                    "sigma0: 0.15}\nrandom: {budget: 70}\ncmaes_solved: {budget: 120, "
                    "explore: 12, restart_growth: 1.5}\n")
    cfg = load_tuning_config(path)
    space = _space()
    g = make_strategy("grid-random", space, cfg, 4)
    assert isinstance(g, GridToRandom) and (g.top_n, g.trials, g.batch, g.seed) == (3, 50, 32, 4)
    assert make_strategy("grid-random", space, cfg, 4, budget=7).trials == 7  # --budget is T
    c = make_strategy("cmaes", space, cfg, 1)
    assert isinstance(c, CmaEs) and (c.budget, c.sigma0) == (90, 0.15)
    assert make_strategy("cmaes", space, cfg, 1, budget=40).budget == 40
    s = make_strategy("cmaes-solved", space, cfg, 3)
    assert isinstance(s, CmaEsSolved) and (s.budget, s.explore, s.restart_growth, s.sigma0) \
        == (120, 12, 1.5, 0.3)
    assert make_strategy("cmaes-solved", space, cfg, 3, budget=10).explore == 10  # ≤ budget
    r = make_strategy("random", space, cfg, 2)
    assert isinstance(r, RandomSearch) and (r.budget, r.batch) == (70, 32)
    with pytest.raises(RvmsimError, match=r"unknown strategy 'annealing' \(known: grid-random, "
                                          r"cmaes, cmaes-solved, random\)"):
        make_strategy("annealing", space, cfg, 0)


@pytest.mark.parametrize("text, key, words", [
    ("parameters: {rad: {range: [500, 100]}}\n", "parameters.rad", "low <= high"),
    ("parameters: {rad: {range: [10, 100]}}\n", "parameters.rad.range", "outside [50, 2000]"),
    ("parameters: {rad: {init: 300, range: [400, 500]}}\n", "parameters.rad.init",
     "outside its range"),
    ("fixed: {tilt: .nan}\n", "fixed.tilt", "finite"),
    ("fixed: {tilt: 400}\n", "fixed.tilt", "outside [-180, 180]"),
    ("fixed: {tilt: " + "9" * 400 + "}\n", "fixed.tilt", "number"),
    ("output: {size: [8192, 8192]}\n", "output.size", "RVMSIM_MAX_IMAGE_PIXELS"),
])
def test_values_that_crashed_a_started_run_are_refused_at_load(tmp_path, text, key, words):
    path = tmp_path / "t.yaml"
    path.write_text(text)
    with pytest.raises(TuningConfigError) as err:
        load_tuning_config(path)
    assert err.value.key == key and words in str(err.value), str(err.value)
    assert err.value.line == 1


def test_an_init_outside_the_cameras_default_range_names_its_key(tmp_path):
    path = tmp_path / "t.yaml"
    path.write_text("tuned: [rad, zoom]\nparameters:\n  rad: {init: 1999}\n")
    cfg = load_tuning_config(path)
    with pytest.raises(TuningConfigError) as err:
        cfg.space(small_render("a").camera)
    assert (err.value.file, err.value.key, err.value.line) == (str(path), "parameters.rad.init", 3)
