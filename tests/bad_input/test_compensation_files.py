"""Bad compensation files and sections, and bad ``--compensation`` uses (issue #25): one
line naming the file and key (or the option), exit 2, before any render, nothing written
over."""

from __future__ import annotations

from pathlib import Path

import pytest

from .conftest import SMALL_SCENE, small_scene
from .harness import REPO, Case, check_case

C, P, OUT = "c.yaml", "p.yaml", "o"


def _robustness(*extra: str) -> tuple[str, ...]:
    return ("robustness", SMALL_SCENE, "--params", P, "--out", OUT, "--samples", "4",
            "--no-progress", "--compensation", *extra)


def _setup(compensation: str | None = None, params: str | None = None):
    def setup(folder: Path) -> None:
        small_scene(folder)
        (folder / P).write_text(params if params is not None else
                                (REPO / "params" / "paper_defaults.yaml").read_text())
        if compensation is not None:
            (folder / C).write_text(compensation)
        (folder / OUT).mkdir()
        (folder / OUT / "robustness.json").write_text('{"earlier": "results"}\n')
    return setup


#: (case id, compensation file text, key named)
FILES = [
    ("unknown-parameter", "params: [h_pan, v_pan, zoom]\n", "params.2"),
    ("pan-alone", "params: [h_pan, tilt]\n", "params"),
    ("negative-sigma", "station: {angle_sigma_deg: -0.1}\n", "station.angle_sigma_deg"),
    ("negative-position-sigma", "station: {position_sigma_mm: -1}\n",
     "station.position_sigma_mm"),
    ("inverted-range", "ranges: {tilt: [2, -2]}\n", "ranges"),
    ("range-without-zero", "ranges: {tilt: [0.5, 2]}\n", "ranges"),
    ("range-of-v-pan", "ranges: {v_pan: [-10, 10]}\n", "ranges"),
    ("range-not-written", "params: [tilt]\nranges: {h_shift: [-5, 5]}\n", "ranges"),
    ("unknown-key", "stations: {}\n", "stations"),
    ("unknown-reference", "reference: sky\n", "reference"),
    ("section-unknown-key", "compensation: {params: [tilt], sigma: 1}\n",
     "compensation.sigma"),
    ("section-not-a-mapping", "compensation: [tilt]\n", "compensation"),
    ("load-state-unknown", "station: {measured_at: parked}\n", "station.measured_at"),
    ("not-a-mapping", "- tilt\n", "mapping"),
    ("bad-yaml", "params: [tilt\n", C),
    ("unknown-law", "law: least-squares\n", "law"),
    ("law-not-a-name", "law: [ec-solve]\n", "law"),
    ("budget-zero", "budget: 0\n", "budget"),
    ("budget-too-large", "budget: 100000\n", "budget"),
    ("budget-not-a-number", "budget: lots\n", "budget"),
    ("budget-fraction", "budget: 12.5\n", "budget"),
    ("unknown-stop", "stop: sometimes\n", "stop"),
    ("negative-edge-sigma", "station: {edge_sigma_px: -0.3}\n", "station.edge_sigma_px"),
    ("unknown-marginal-policy", "station: {marginal: maybe}\n", "station.marginal"),
    ("section-unknown-law", "compensation: {law: ec_solve}\n", "compensation.law"),
]
CASES = [Case(f"compensation-{i}", _robustness(C), (C, key), _setup(text), keep=(OUT,))
         for i, text, key in FILES]
CASES += [
    Case("compensation-file-missing", _robustness("nope.yaml"), ("nope.yaml", "not found"),
         _setup(), keep=(OUT,)),
    # a setting whose RVM image shows no ground: the law has nothing to hold in place
    Case("compensation-target-not-in-view", _robustness("default"), (SMALL_SCENE, "reference"),
         _setup(params="h_pan: 90\nv_pan: -90\nzoom: 3\n"), keep=(OUT,)),
    Case("tune-compensation-without-robust",
         ("tune", SMALL_SCENE, "--out", OUT, "--compensation", "default", "--no-progress"),
         ("--compensation", "--robust"), _setup(), keep=(OUT,)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_compensation_input(case, tmp_path):
    check_case(case, tmp_path)
