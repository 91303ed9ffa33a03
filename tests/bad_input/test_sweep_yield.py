"""Bad values of the sweep file's yield settings (``robustness``, issue #16): one line
naming the sweep file and the key, exit 2, before anything runs."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE
from .harness import ENDLESS, Case, check_case

S = "s.yaml"
SWEEP = ("sweep", S, "--out", "so", "--workers", "1", "--no-progress")


def _file(robustness: str):
    return lambda folder: (folder / S).write_text(
        f"name: bad\nbase_scene: {SMALL_SCENE}\n"
        "tune: {strategy: random, budget: 4, recheck: {rounds: 0}}\n"
        f"robustness: {robustness}\n"
        "axes:\n  pitch_deg: [28]\n")


#: (case id, the robustness value, key named)
FILES = [
    ("samples-negative", "{samples: -1}", "robustness.samples"),
    ("samples-huge", "{samples: 100000}", "robustness.samples"),
    ("samples-400-digits", "{samples: " + "9" * 400 + "}", "robustness.samples"),
    ("samples-text", "{samples: many}", "robustness.samples"),
    ("samples-quoted-number", "{samples: '64'}", "robustness.samples"),
    ("samples-bool", "{samples: true}", "robustness.samples"),
    ("samples-fraction", "{samples: 6.5}", "robustness.samples"),
    ("samples-null", "{samples: null}", "robustness.samples"),
    ("seed-negative", "{seed: -3}", "robustness.seed"),
    ("seed-huge", "{seed: 99999999999}", "robustness.seed"),
    ("seed-text", "{seed: zero}", "robustness.seed"),
    ("seed-nan", "{seed: .nan}", "robustness.seed"),
    ("unknown-key", "{sample: 64}", "robustness.sample"),
    ("scales-not-a-key", "{samples: 8, scales: [1, 2]}", "robustness.scales"),
    ("not-a-mapping", "64", "robustness"),
    ("a-list", "[64, 0]", "robustness"),
]
#: Cases run in a child of their own: endless sample counts.
ISOLATED = {"samples-huge": ENDLESS, "samples-400-digits": ENDLESS}
CASES = [Case(f"sweep-yield-{i}", SWEEP, (S, key), _file(value),
              isolate=ISOLATED.get(i, "")) for i, value, key in FILES]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_yield_setting(case, case_dir):
    check_case(case, case_dir)
