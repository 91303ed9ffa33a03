"""Many tasks at once: executors (local processes, Dask) and design-stage sweeps."""

from __future__ import annotations

from .executors import (
    Executor,
    LocalExecutor,
    DaskExecutor,
    make_executor,
    task_malloc,
)
from .sweep import (
    AXES,
    SweepSpec,
    DesignPoint,
    load_sweep,
    design_points,
    run_point,
    run_sweep,
    SweepStore,
    SweepResult,
    sweep_table,
    write_sweep_outputs,
)

__all__ = [
    "Executor",
    "LocalExecutor",
    "DaskExecutor",
    "make_executor",
    "task_malloc",
    "AXES",
    "SweepSpec",
    "DesignPoint",
    "load_sweep",
    "design_points",
    "run_point",
    "run_sweep",
    "SweepStore",
    "SweepResult",
    "sweep_table",
    "write_sweep_outputs",
]
