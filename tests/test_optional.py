"""rvmsim/_optional.py: the heavy modules a process that evaluates candidates never needs are
imported only when used, and then they work."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from rvmsim._optional import cma_class, import_trimesh, scipy_stats
from rvmsim.robust import AxisDistribution, Variation, draw_samples

#: Imported on first use only (each costs a spawned worker or child command 0.3–0.6 s).
DEFERRED = ("cmaes", "scipy.stats", "trimesh", "pyrender", "distributed", "playwright")


def test_the_cli_and_the_evaluators_import_none_of_the_deferred_modules():
    """A fresh interpreter importing the command line, the tuner and the evaluators (what a
    spawned worker imports) loads none of them."""
    code = ("import sys, rvmsim.cli, rvmsim.tune, rvmsim.pipeline, rvmsim.batch, rvmsim.robust; "
            f"print([m for m in {DEFERRED!r} if m in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]", out.stdout


def test_the_deferred_modules_work_when_used():
    """The loaders give the real modules: a CMA-ES step, a truncated normal, a mesh, and
    variation samples drawn through scipy.stats."""
    opt = cma_class()(mean=np.zeros(2), sigma=0.5, seed=1)
    assert opt.ask().shape == (2,)
    assert abs(scipy_stats().truncnorm.ppf(0.5, -2, 2)) < 1e-12
    assert import_trimesh().creation.box().is_watertight
    turn = AxisDistribution("normal", sigma=1.0, truncate=2.0)
    samples = draw_samples(Variation(axes=(AxisDistribution(),) * 3 + (turn,) * 3), 8, seed=0)
    yaws = [s.offsets[3] for s in samples]
    assert len(samples) == 8 and all(abs(y) <= 2.0 for y in yaws) and len(set(yaws)) == 8
