"""Bad display values (EC 1-6's display model) in a scene's or a criteria file's `display:`
section, and bad EC parameters: one line naming the file and the key."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE, small_scene
from .harness import Case, check_case

C = "c.yaml"


def _evaluate(criteria: str) -> tuple[str, ...]:
    return ("evaluate", SMALL_SCENE, "--criteria", criteria, "--out", "e", "--no-progress")


def _scene(key: str, value):
    return lambda folder: small_scene(folder, {f"display.{key}": value})


def _file(text: str):
    return lambda folder: (folder / C).write_text(text)


#: (case id, display key, bad value)
SCENE_VALUES = [
    ("width-zero", "width_mm", 0),
    ("height-negative", "height_mm", -85.0),
    ("eye-distance-nan", "eye_distance_mm", float("nan")),
    ("eye-distance-inf", "eye_distance_mm", float("inf")),
    ("resolution-zero", "resolution_px", [0, 480]),
    ("resolution-negative", "resolution_px", [800, -480]),
    ("viewing-angle-90", "viewing_angle_deg", 90.0),
    ("unknown-key", "diagonal_in", 7.0),
]
CASES = [Case(f"display-scene-{i}", _evaluate("fmvss111-full"), (SMALL_SCENE, f"display.{key}"),
              _scene(key, value)) for i, key, value in SCENE_VALUES]
#: (case id, criteria file text, key named)
FILES = [
    ("width-zero", "display: {width_mm: 0}\n", "display.width_mm"),
    ("height-nan", "display: {height_mm: .nan}\n", "display.height_mm"),
    ("eye-distance-negative", "display: {eye_distance_mm: -700}\n", "display.eye_distance_mm"),
    ("resolution-nan", "display: {resolution_px: [.nan, 480]}\n", "display.resolution_px.0"),
    ("parameter-unknown", "plugins: [rvmsim.regulations.fmvss111.ecs]\n"
     "criteria: {6-1: {parameters: {max_zoom: 2}}}\n", "criteria.6-1.parameters.max_zoom"),
    ("parameter-nan", "plugins: [rvmsim.regulations.fmvss111.ecs]\n"
     "criteria: {6-1: {parameters: {max_magnification: .nan}}}\n",
     "criteria.6-1.parameters.max_magnification"),
]
CASES += [Case(f"display-criteria-{i}", _evaluate(C), (C, key), _file(text))
          for i, text, key in FILES]
CASES += [
    Case("display-tune-width-zero", ("tune", SMALL_SCENE, "--criteria", "fmvss111-full", "--out",
                                     "new", "--no-progress"),
         (SMALL_SCENE, "display.width_mm"), _scene("width_mm", 0.0)),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_display(case, case_dir):
    check_case(case, case_dir)
