"""Bad scene files through the command line (issue #14, groups 1 and 2): one case per error
class (a value refused, a sensor over the pixel limit, YAML over the limits, the limit set by
the environment).  Every bad value of every section is the library's contract,
tests/scene/test_bad_values.py."""

from __future__ import annotations

import math

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE, small_scene
from .harness import MEMORY, Case, check_case

RENDER = ("render", SMALL_SCENE, "--out", "r", "--no-progress")


def _edit(key: str, value, *more) -> object:
    edits = {key: value, **dict(zip(more[::2], more[1::2]))}
    return lambda folder: small_scene(folder, edits)


def _yaml_bomb(text: str):
    def setup(folder):
        scene = small_scene(folder)
        scene.write_text(scene.read_text() + text)
    return setup


#: One case per error class through the command line (the values themselves are the
#: library's contract, tests/scene/test_bad_values.py): a value the schema refuses, a sensor
#: over the pixel limit (in a capped child: a regression would allocate it), the YAML limits,
#: and a limit raised or lowered by the environment.
CASES = (
    [Case("scene-fx-inf", RENDER, (SMALL_SCENE, "camera.intrinsics.fx"),
          _edit("camera.intrinsics.fx", math.inf)),
     Case("tune-size-huge", ("tune", SMALL_SCENE, "--out", "new", "--budget", "4",
                             "--strategy", "random", "--workers", "1", "--no-progress"),
          (SMALL_SCENE, "camera.image_size"), _edit("camera.image_size", [100000, 100000]),
          isolate=MEMORY)]
    + [Case(f"scene-yaml-{i}", RENDER, (SMALL_SCENE, "limit"), _yaml_bomb(text), isolate=why)
       for i, text, why in BOMBS]
    + [Case("render-scaled-over-the-limit", RENDER + ("--scale", "4"),
            (SMALL_SCENE, "camera.image_size", "RVMSIM_MAX_IMAGE_PIXELS"),
            _edit("name", "scaled"), env={"RVMSIM_MAX_IMAGE_PIXELS": "1000000"})]
)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_scene_file(case, case_dir):
    check_case(case, case_dir)
