"""Fixtures of the bad-input cases: a small valid scene to break, and a finished run and
sweep folder (made once) that cases copy and must leave byte-identical."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from .harness import REPO, run_rvmsim

#: A small scene (320×240 sensor) of vehicle A: quick to render in a case.
SMALL_SCENE = "scene.yaml"


def write_small_scene(folder: Path, edit: dict | None = None) -> Path:
    """Vehicle A at a quarter of its sensor, as ``folder/scene.yaml`` (``edit``: dotted keys
    set to values, ``None`` deletes the key)."""
    import yaml

    doc = yaml.safe_load((REPO / "scenes" / "vehicle_a.yaml").read_text())
    doc["camera"]["image_size"] = [320, 240]
    intr = doc["camera"]["intrinsics"]
    for k in ("fx", "fy"):
        intr[k] = float(intr[k]) / 4
    for key, value in (edit or {}).items():
        node = doc
        *path, last = key.split(".")
        for p in path:
            node = node[int(p)] if isinstance(node, list) else node.setdefault(p, {})
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    path = folder / SMALL_SCENE
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


@pytest.fixture(scope="session")
def finished_run(tmp_path_factory) -> Path:
    """A finished tuning run of the small scene (random search, 40 evaluations)."""
    folder = tmp_path_factory.mktemp("finished")
    write_small_scene(folder)
    out = run_rvmsim(["tune", SMALL_SCENE, "--strategy", "random", "--budget", "40",
                      "--workers", "1", "--out", "run", "--no-progress"], cwd=folder)
    assert out.code == 0, out.stderr
    return folder


@pytest.fixture
def case_dir(tmp_path, finished_run) -> Path:
    """A fresh case folder holding ``scene.yaml`` (valid) and ``run/`` (a finished run)."""
    shutil.copy(finished_run / SMALL_SCENE, tmp_path / SMALL_SCENE)
    shutil.copytree(finished_run / "run", tmp_path / "run")
    return tmp_path
