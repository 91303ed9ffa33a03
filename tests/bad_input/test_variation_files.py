"""Bad variation files, bad variation sections of scenes and bad ``rvmsim robustness`` flags
(issue #16): one line naming the file and key (or the option), exit 2, before any render."""

from __future__ import annotations

from pathlib import Path

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE, small_scene
from .harness import DASK, REPO, Case, check_case

V, P = "v.yaml", "p.yaml"
BIG = "9" * 400


def _robustness(*extra: str, params: bool = True) -> tuple[str, ...]:
    head = ("robustness", SMALL_SCENE) + (("--params", P) if params else ())
    return head + ("--out", "o", "--samples", "4", "--no-progress", *extra)


def _setup(variation: str | None = None, scene_edit: dict | None = None,
           params: str | None = None):
    def setup(folder: Path) -> None:
        small_scene(folder, scene_edit)
        (folder / P).write_text(params if params is not None else
                                (REPO / "params" / "paper_defaults.yaml").read_text())
        if variation is not None:
            (folder / V).write_text(variation)
    return setup


#: (case id, variation file text, key named)
FILES = [
    ("unknown-key", "mount: {yaw: {uniform: {half_width: 1}}}\n", "mount.yaw"),
    ("unknown-distribution", "mount: {yaw_deg: {triangular: {half_width: 1}}}\n",
     "mount.yaw_deg.triangular"),
    ("two-distributions", "mount: {yaw_deg: {uniform: {half_width: 1}, normal: {sigma: 1}}}\n",
     "mount.yaw_deg"),
    ("negative-half-width", "mount: {x_mm: {uniform: {half_width: -1}}}\n",
     "mount.x_mm.uniform.half_width"),
    ("nan-sigma", "mount: {pitch_deg: {normal: {sigma: .nan}}}\n", "mount.pitch_deg.normal.sigma"),
    ("huge-half-width", f"mount: {{z_mm: {{uniform: {{half_width: {BIG}}}}}}}\n", "mount.z_mm"),
    ("too-wide", "mount: {roll_deg: {uniform: {half_width: 45}}}\n", "mount.roll_deg"),
    ("zero-truncate", "mount: {roll_deg: {normal: {sigma: 1, truncate: 0}}}\n",
     "mount.roll_deg.normal.truncate"),
    ("levels-zero", "mount: {position_levels: 0}\n", "mount.position_levels"),
    ("levels-text", "mount: {position_levels: many}\n", "mount.position_levels"),
    ("load-no-name", "load_states: [{height_mm: -30}]\n", "load_states.0.name"),
    ("load-same-names", "load_states: [{name: a}, {name: a}]\n", "load_states"),
    ("load-zero-weight", "load_states: [{name: a, weight: 0}]\n", "load_states.0.weight"),
    ("load-drop-metres", "load_states: [{name: a, height_mm: -3000}]\n",
     "load_states.0.height_mm"),
    ("load-states-mapping", "load_states: {name: a}\n", "load_states"),
    ("not-a-mapping", "- 1\n- 2\n", "mapping"),
    ("bad-yaml", "mount: {x_mm: [\n", V),
]
CASES = [Case(f"variation-{i}", _robustness("--variation", V), (V, key), _setup(text))
         for i, text, key in FILES]
CASES += [Case(f"variation-yaml-{i}", _robustness("--variation", V), (V, "limit"),
               _setup("mount: {}\n" + text), isolate=why) for i, text, why in BOMBS]
CASES += [
    Case("variation-file-missing", _robustness("--variation", "nope.yaml"),
         ("nope.yaml", "not found"), _setup()),
    Case("variation-file-is-folder", _robustness("--variation", "."), (".", "variation"),
         _setup()),
    Case("scene-section-negative",
         _robustness(), (SMALL_SCENE, "variation.mount.pitch_deg.uniform.half_width"),
         _setup(scene_edit={"variation.mount.pitch_deg.uniform.half_width": -1})),
    Case("scene-section-unknown-key",
         _robustness(), (SMALL_SCENE, "variation.mounting"),
         _setup(scene_edit={"variation.mounting": {}})),
    Case("scene-section-missing", _robustness(), (SMALL_SCENE, "variation"),
         _setup(scene_edit={"variation": None})),
    Case("params-nan", _robustness(), (P, "rad"), _setup(params="rad: .nan\n")),
    Case("criteria-missing", _robustness("--criteria", "c.yaml"), ("c.yaml",), _setup()),
]
#: (case id, extra arguments, option named)
FLAGS = [
    ("samples-zero", ("--samples", "0"), "--samples"),
    ("samples-text", ("--samples", "many"), "--samples"),
    ("min-yield-above-1", ("--min-yield", "1.5"), "--min-yield"),
    ("min-yield-nan", ("--min-yield", "nan"), "--min-yield"),
    ("seed-negative", ("--seed", "-1"), "--seed"),
    ("scale-zero", ("--scale", "0"), "--scale"),
    ("scale-samples-zero", ("--scale-samples", "0"), "--scale-samples"),
    ("unknown-option", ("--robust",), "--robust"),
    ("scales-text", ("--scales", "0.5,big"), "--scales"),
    ("scales-negative", ("--scales", "-1"), "--scales"),
    ("scales-nan", ("--scales", "1,nan"), "--scales"),
    ("scales-empty", ("--scales", ""), "--scales"),
    ("workers-zero", ("--workers", "0"), "--workers"),
    ("workers-text", ("--workers", "two"), "--workers"),
    ("scheduler-no-port", ("--scheduler", "tcp://127.0.0.1"), "--scheduler"),
    ("scheduler-unreachable", ("--scheduler", "tcp://127.0.0.1:9"), "127.0.0.1:9"),
]
CASES += [Case(f"flag-{i}", _robustness(*extra), (opt,), _setup(),
               isolate=DASK if i == "scheduler-unreachable" else "") for i, extra, opt in FLAGS]
CASES += [
    Case("flag-params-missing", _robustness(params=False), ("--params",), _setup()),
    Case("flag-out-is-a-file", ("robustness", SMALL_SCENE, "--params", P, "--out", P),
         ("--out", P), _setup()),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_variation_input(case, tmp_path):
    check_case(case, tmp_path)
