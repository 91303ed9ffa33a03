"""Shared by the benchmarks in tools/: machine description, tuning-like parameter ranges."""

from __future__ import annotations

import platform
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rvmsim.isp import IspParams

if TYPE_CHECKING:
    from rvmsim.search import SearchSpace, TuningConfig

#: Ranges a tuning run explores around the paper's defaults (inside Table 2's ranges), for
#: the 1280×960 bundled sensors.
SEARCH = {
    "fov": (160.0, 200.0), "rad": (450.0, 800.0), "h_shift": (-60.0, 60.0),
    "v_shift": (-80.0, 80.0), "zoom": (0.4, 1.5), "adv_h_shift": (-0.3, 0.3),
    "adv_v_shift": (-0.5, 0.5), "adv_h_scale": (0.7, 1.5), "adv_v_scale": (0.7, 1.5),
}


def random_candidates(n: int, seed: int = 0) -> list[IspParams]:
    rng = np.random.default_rng(seed)
    return [IspParams(**{k: rng.uniform(*r) for k, r in SEARCH.items()}) for _ in range(n)]


def cpu_model() -> str:
    """The CPU's model name (for benchmark reports)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def protocol_candidates(space: SearchSpace, config: TuningConfig, n: int) -> list[np.ndarray]:
    """``n`` parameter vectors like the paper protocol's: half drawn from its 3⁹ coarse grid,
    half fine-stage-like (uniform draws one grid step around the grid's centre), seed 0."""
    from rvmsim.search import make_strategy

    strat = make_strategy("grid-random", space, config, 0, 2000)
    gen = strat.batches()
    grid: list[np.ndarray] = []
    told = None
    while True:
        try:
            stage, xs = gen.send(told) if told is not None else next(gen)
        except StopIteration:
            break
        if stage != "coarse":
            break
        grid += list(xs)
        told = [(0.0, 0.0)] * len(xs)
    rng = np.random.default_rng(0)
    picked = [grid[i] for i in rng.choice(len(grid), n // 2, replace=False)]
    mid, step = (space.low + space.high) / 2.0, (space.high - space.low) / 4.0
    fine = [mid + (rng.random(len(mid)) * 2.0 - 1.0) * step for _ in range(n - n // 2)]
    return picked + fine
