"""A NUL byte in a path named inside a file (issue #45): a scene's ``sites:`` entry, a mesh
path, a sweep's ``base_scene`` and a criteria file's ``plugins:`` entry are refused with one
line naming the file and the key, exit 2, no traceback (no ``embedded null byte``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from .conftest import SMALL_SCENE, small_scene
from .harness import Case, check_case


def _scene(edit: dict[str, Any]) -> Callable[[Path], None]:
    def setup(folder: Path) -> None:
        small_scene(folder, edit)
    return setup


def _file(name: str, text: str) -> Callable[[Path], None]:
    def setup(folder: Path) -> None:
        (folder / name).write_text(text)
    return setup


CASES = [
    Case("sites entry", ("render", SMALL_SCENE, "--out", "out"), (SMALL_SCENE, "sites", "NUL"),
         _scene({"sites": ["site\x00.yaml"]})),
    Case("mesh path", ("render", SMALL_SCENE, "--out", "out"),
         (SMALL_SCENE, "vehicle.bumper", "NUL"),
         _scene({"vehicle.bumper": {"mesh": "bumper\x00.stl"}})),
    Case("sweep base_scene", ("sweep", "sweep.yaml", "--out", "sw"),
         ("sweep.yaml", "base_scene", "NUL"),
         _file("sweep.yaml", 'name: t\nbase_scene: "sc\\0ene.yaml"\n'
                             "axes:\n  camera_height_m: [0.9, 1.0]\n")),
    Case("criteria plugins entry", ("evaluate", SMALL_SCENE, "--criteria", "crit.yaml",
                                    "--out", "out"), ("crit.yaml", "plugins", "NUL"),
         _file("crit.yaml", 'plugins: ["./pl\\0ug.py"]\n')),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_a_nul_in_a_named_path_is_one_line_and_exit_2(case: Case, case_dir: Path) -> None:
    out = check_case(case, case_dir)
    assert "null byte" not in out.stderr
    assert not (case_dir / "out").exists() and not (case_dir / "sw").exists()
