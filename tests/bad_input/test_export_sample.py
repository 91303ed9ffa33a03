"""Bad ``load_state`` sections and ``--export-sample`` numbers (issue #25 item 7): one stderr
line naming the file and key (or the option), exit status 2, no traceback, nothing written
over."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE, small_scene
from .harness import Case, check_case

S = SMALL_SCENE
ROBUST = ("robustness", S, "--params", "p.yaml", "--samples", "4", "--scales", "1",
          "--workers", "1", "--no-progress")


def _params(folder):
    (folder / "p.yaml").write_text("zoom: 0.8\n")


def _loaded(**load):
    def setup(folder):
        _params(folder)
        small_scene(folder, {"load_state": {"name": "full", "height_mm": -45, "pitch_deg": 0.9,
                                            **load}})
    return setup


CASES = [
    Case("export-sample-past-the-samples", (*ROBUST, "--export-sample", "4", "--out", "run"),
         ("--export-sample", "no sample 4"), _params, keep=("run",)),
    Case("export-sample-negative", (*ROBUST, "--export-sample", "-1", "--out", "run"),
         ("--export-sample",), _params, keep=("run",)),
    Case("export-sample-not-a-number", (*ROBUST, "--export-sample", "two", "--out", "run"),
         ("--export-sample",), _params, keep=("run",)),
    Case("load-state-height-out-of-range", ("render", S, "--out", "r", "--no-progress"),
         (S, "load_state.height_mm"), _loaded(height_mm=-400)),
    Case("load-state-pitch-out-of-range", ("evaluate", S, "--out", "r", "--no-progress"),
         (S, "load_state.pitch_deg"), _loaded(pitch_deg=15)),
    Case("load-state-unknown-key", ("render", S, "--out", "r", "--no-progress"),
         (S, "load_state.weight"), _loaded(weight=0.5)),
    Case("load-state-pivot-nan", ("render", S, "--out", "r", "--no-progress"),
         (S, "load_state.pivot_m.1"), _loaded(pivot_m=[0.0, float("nan"), 0.0])),
    Case("load-state-out-of-range-in-robustness", (*ROBUST, "--out", "new"),
         (S, "load_state.height_mm"), _loaded(height_mm=400)),
    Case("loaded-scene-in-robustness", (*ROBUST, "--export-sample", "1", "--out", "new"),
         (S, "load_state"), _loaded()),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_export_input(case, case_dir):
    check_case(case, case_dir)
