"""Bad criteria files (issue #14, groups 1 and 2): NaN thresholds and coefficients, huge
integers, and files over the YAML limits."""

from __future__ import annotations

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE
from .harness import Case, check_case

C = "c.yaml"
EVALUATE = ("evaluate", SMALL_SCENE, "--criteria", C, "--out", "e", "--no-progress")


def _file(text: str):
    return lambda folder: (folder / C).write_text(text)


#: (case id, text, key named)
FILES = [
    ("range-nan", "criteria: {2-1: {range: [.nan, 9]}}\n", "criteria.2-1.range.0"),
    ("range-high-nan", "criteria: {2-1: {range: [5, .nan]}}\n", "criteria.2-1.range.1"),
    ("tolerance-inf", "criteria: {2-1: {range: [5, 9], tolerance: .inf}}\n",
     "criteria.2-1.tolerance"),
    ("tolerance-nan", "criteria: {2-1: {range: [5, 9], tolerance: .nan}}\n",
     "criteria.2-1.tolerance"),
    ("sigmoid-c1-nan", "criteria: {2-1: {sigmoid: {c1: .nan}}}\n", "criteria.2-1.sigmoid.c1"),
    ("sigmoid-c2-nan", "criteria: {2-1: {sigmoid: {c2: .nan}}}\n", "criteria.2-1.sigmoid.c2"),
    ("sigmoid-c3-inf", "criteria: {2-1: {sigmoid: {c3: .inf}}}\n", "criteria.2-1.sigmoid.c3"),
    ("upper-fraction-nan", "upper_region_fraction: .nan\n", "upper_region_fraction"),
    ("edge-columns-400-digits", "edge_columns: " + "9" * 400 + "\n", "edge_columns"),
]
CASES = [Case(f"criteria-{i}", EVALUATE, (C, key), _file(text))
         for i, text, key in FILES]
CASES += [Case(f"criteria-yaml-{i}", EVALUATE, (C, "limit"), _file("name: x\n" + text), isolate=why) for i, text, why in BOMBS]
CASES += [
    Case("criteria-tune-range-nan", ("tune", SMALL_SCENE, "--criteria", C, "--out", "new",
                                     "--no-progress"),
         (C, "criteria.2-1.range.0"), _file("criteria: {2-1: {range: [.nan, 9]}}\n")),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_criteria_file(case, case_dir):
    check_case(case, case_dir)
