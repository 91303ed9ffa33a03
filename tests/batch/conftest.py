"""Shared sweep fixtures: vehicle A at 320 × 240 as a base scene, a six-point sweep run once
on local processes, and a Dask LocalCluster on loopback (both for the whole package)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rvmsim.batch import LocalExecutor, RecheckSettings, load_sweep, run_sweep

from rvmsim.testing.scenes import small_scene_text

SWEEP = """\
name: tiny mount study
base_scene: base.yaml
axes:
  camera_height_m: [0.9, 1.0, 1.1]
  pitch_deg: [28, 34]
tune:
  strategy: cmaes
  budget: 200
  seed: 3
  config: {output: {size: [320, 180]}}
"""


def write_sweep(folder: Path, text: str = SWEEP, variation: dict | None = None) -> Path:
    """Vehicle A at 320 × 240 as the base scene (without the bundled variation section, so
    its sweeps measure no yield; with ``variation`` if given), and a sweep."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "base.yaml").write_text(small_scene_text("a", variation=variation))
    (folder / "sweep.yaml").write_text(text)
    return folder / "sweep.yaml"


@pytest.fixture(scope="package")
def sweep_file(tmp_path_factory) -> Path:
    return write_sweep(tmp_path_factory.mktemp("sweep"))


@pytest.fixture(scope="package")
def local_run(sweep_file):
    """The first pass only (no re-check rounds): the executors and the store under test."""
    spec = dataclasses.replace(load_sweep(sweep_file), recheck=RecheckSettings(rounds=0))
    res = run_sweep(spec, sweep_file.parent / "local", executor=LocalExecutor(2))
    return spec, res


@pytest.fixture(scope="package")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=":0") as c, \
            distributed.Client(c) as client:
        yield c, client
