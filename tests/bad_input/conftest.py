"""Fixtures of the bad-input cases: a small valid scene to break, and a finished run and
sweep folder (made once) that cases copy and must leave byte-identical."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path
from typing import Any

import pytest

from ..cli_runner import run_in_process, tune_status
from rvmsim.testing.scenes import write_small_scene

#: The file name of the small scene (vehicle A on a 320×240 sensor) in a case folder.
SMALL_SCENE = "scene.yaml"


def small_scene(folder: Path, edit: dict[str, Any] | None = None) -> Path:
    """Vehicle A at a quarter of its sensor (:func:`tests.scenes.write_small_scene`) as
    ``folder/scene.yaml``; ``edit``: dotted keys set to values (None deletes the key)."""
    return write_small_scene(folder, "a", name=SMALL_SCENE, edit=edit)


@pytest.fixture(scope="session")
def finished_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished tuning run of the small scene (random search, 40 evaluations)."""
    folder = tmp_path_factory.mktemp("finished")
    small_scene(folder)
    out = run_in_process(["tune", SMALL_SCENE, "--strategy", "random", "--budget", "40",
                          "--workers", "1", "--out", "run", "--no-progress"], cwd=folder)
    assert out.code == tune_status(folder / "run"), out.stderr
    return folder


@pytest.fixture
def case_dir(tmp_path: Path, request: pytest.FixtureRequest) -> Path:
    """A fresh case folder holding ``scene.yaml`` (valid), and ``run/`` (a finished run) when
    the test's ``case`` names it (:meth:`~.harness.Case.gives`) or the test has no ``case``."""
    callspec = getattr(request.node, "callspec", None)
    case = None if callspec is None else callspec.params.get("case")
    if case is not None and not case.gives("run"):
        small_scene(tmp_path)
        return tmp_path
    finished_run: Path = request.getfixturevalue("finished_run")
    shutil.copy(finished_run / SMALL_SCENE, tmp_path / SMALL_SCENE)
    shutil.copytree(finished_run / "run", tmp_path / "run")
    return tmp_path


@pytest.fixture
def plugin_module(tmp_path, monkeypatch, request):
    """A writer of importable plugin modules (``name`` → source), found on ``sys.path`` (and
    on a child's ``PYTHONPATH``) and forgotten after the test."""
    folder = tmp_path / "plugins"
    folder.mkdir()
    monkeypatch.syspath_prepend(str(folder))
    made: list[str] = []

    def write(source: str) -> str:
        name = f"rvmsim_test_hostile_{request.node.name.translate(str.maketrans('[]-', '___'))}"
        name += f"_{len(made)}"
        (folder / f"{name}.py").write_text(source)
        made.append(name)
        return name

    write.folder = folder
    yield write
    for name in made:
        sys.modules.pop(name, None)
