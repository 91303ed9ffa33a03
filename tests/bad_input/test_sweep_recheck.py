"""Bad values of the sweep file's re-check settings (``tune.recheck``, issue #15): one line
naming the sweep file and the key, exit 2, before anything runs."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE
from .harness import ENDLESS, Case, check_case

S = "s.yaml"
SWEEP = ("sweep", S, "--out", "so", "--workers", "1", "--no-progress")


def _file(recheck: str):
    return lambda folder: (folder / S).write_text(
        f"name: bad\nbase_scene: {SMALL_SCENE}\n"
        f"tune: {{strategy: random, budget: 4, recheck: {recheck}}}\n"
        "axes:\n  pitch_deg: [28]\n")


#: (case id, the recheck value, key named)
FILES = [
    ("rounds-negative", "{rounds: -1}", "tune.recheck.rounds"),
    ("rounds-huge", "{rounds: 1000000}", "tune.recheck.rounds"),
    ("rounds-text", "{rounds: three}", "tune.recheck.rounds"),
    ("rounds-bool", "{rounds: true}", "tune.recheck.rounds"),
    ("rounds-fraction", "{rounds: 1.5}", "tune.recheck.rounds"),
    ("rounds-400-digits", "{rounds: " + "9" * 400 + "}", "tune.recheck.rounds"),
    ("factor-below-one", "{budget_factor: 0.5}", "tune.recheck.budget_factor"),
    ("factor-nan", "{budget_factor: .nan}", "tune.recheck.budget_factor"),
    ("factor-inf", "{budget_factor: .inf}", "tune.recheck.budget_factor"),
    ("factor-text", "{budget_factor: '2'}", "tune.recheck.budget_factor"),
    ("factor-huge", "{budget_factor: 1.0e300}", "tune.recheck.budget_factor"),
    ("neighbours-negative", "{neighbours: -1}", "tune.recheck.neighbours"),
    ("neighbours-many", "{neighbours: 27}", "tune.recheck.neighbours"),
    ("unknown-key", "{round: 2}", "tune.recheck.round"),
    ("not-a-mapping", "5", "tune.recheck"),
    ("a-list", "[1, 2]", "tune.recheck"),
]
#: Cases run in a child of their own: endless re-check rounds or budgets.
ISOLATED = {"rounds-huge": ENDLESS, "rounds-400-digits": ENDLESS, "factor-inf": ENDLESS,
            "factor-huge": ENDLESS}
CASES = [Case(f"sweep-recheck-{i}", SWEEP, (S, key), _file(value),
              isolate=ISOLATED.get(i, "")) for i, value, key in FILES]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_recheck_setting(case, case_dir):
    check_case(case, case_dir)
