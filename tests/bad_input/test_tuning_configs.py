"""Bad tuning configs (issue #14, groups 1-3): ranges, initial and fixed values that used to
crash after the run had started are refused when the file is read; RVM output sizes over
the limits; files over the YAML limits."""

from __future__ import annotations

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE
from .harness import MEMORY, Case, check_case

T = "t.yaml"
TUNE = ("tune", SMALL_SCENE, "--config", T, "--out", "new", "--strategy", "random",
        "--budget", "4", "--workers", "1", "--no-progress")


def _file(text: str):
    return lambda folder: (folder / T).write_text(text)


BIG = "9" * 400
#: (case id, text, key named)
FILES = [
    ("range-reversed", "parameters: {rad: {range: [500, 100]}}\n", "parameters.rad"),
    ("range-below-spec", "parameters: {rad: {range: [10, 100]}}\n", "parameters.rad.range"),
    ("range-above-spec", "parameters: {zoom: {range: [1, 50]}}\n", "parameters.zoom.range"),
    ("range-nan", "parameters: {rad: {range: [.nan, 500]}}\n", "parameters.rad.range.0"),
    ("range-inf", "parameters: {rad: {range: [100, .inf]}}\n", "parameters.rad.range.1"),
    ("init-outside-spec", "parameters: {rad: {init: 3000}}\n", "parameters.rad.init"),
    ("init-outside-range", "parameters: {rad: {init: 300, range: [400, 500]}}\n",
     "parameters.rad.init"),
    ("init-nan", "parameters: {zoom: {init: .nan}}\n", "parameters.zoom.init"),
    ("step-inf", "parameters: {rad: {step: .inf}}\n", "parameters.rad.step"),
    ("fixed-nan", "fixed: {tilt: .nan}\n", "fixed.tilt"),
    ("fixed-inf", "fixed: {tilt: -.inf}\n", "fixed.tilt"),
    ("fixed-outside-spec", "fixed: {tilt: 400}\n", "fixed.tilt"),
    ("fixed-400-digits", f"fixed: {{tilt: {BIG}}}\n", "fixed.tilt"),
    ("size-huge", "output: {size: [100000, 100000]}\n", "output.size"),
    ("size-pixels", "output: {size: [8192, 8192]}\n", "output.size"),
    ("top-m-400-digits", f"top_m: {BIG}\n", "top_m"),
    ("batch-400-digits", f"batch: {BIG}\n", "batch"),
    # the default strategy's settings (issue #15)
    ("solved-growth-too-big", "cmaes_solved: {restart_growth: 9}\n", "cmaes_solved.restart_growth"),
    ("solved-growth-nan", "cmaes_solved: {restart_growth: .nan}\n", "cmaes_solved.restart_growth"),
    ("solved-explore-negative", "cmaes_solved: {explore: -1}\n", "cmaes_solved.explore"),
    ("solved-budget-zero", "cmaes_solved: {budget: 0}\n", "cmaes_solved.budget"),
    ("solved-unknown-setting", "cmaes_solved: {popsize: 12}\n", "cmaes_solved.popsize"),
]
#: Cases run in a child of their own: RVM images over the pixel limit.
ISOLATED = {"size-huge": MEMORY, "size-pixels": MEMORY}
CASES = [Case(f"tuning-{i}", TUNE, (T, key), _file(text),
              isolate=ISOLATED.get(i, "")) for i, text, key in FILES]
CASES += [Case(f"tuning-yaml-{i}", TUNE, (T, "limit"), _file("top_m: 5\n" + text), isolate=why) for i, text, why in BOMBS]
CASES += [
    Case("tuning-init-outside-camera-range", TUNE, (T, "parameters.rad.init"),
         _file("parameters: {rad: {init: 1900}}\n")),
    Case("tuning-default-strategy", TUNE[:6] + TUNE[8:], (T, "cmaes_solved.sigma0"),
         _file("cmaes_solved: {sigma0: 0}\n")),
    Case("tuning-batch-command", ("batch", SMALL_SCENE, "--config", T, "--out", "b",
                                  "--no-progress"),
         (T, "fixed.tilt"), _file("fixed: {tilt: .nan}\n")),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_tuning_config(case, case_dir):
    check_case(case, case_dir)
