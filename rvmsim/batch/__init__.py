"""Many tasks at once: executors (local processes, Dask), design-stage sweeps, and batches of
tuning runs.

- :mod:`.executors`: where tasks run (local processes or a Dask cluster).
- :mod:`.spec`: the sweep file, its axes and design points.
- :mod:`.point`: one design point as a task (render, infeasibility, tune, sensitivity);
  :mod:`.probes`: what it shares with markets points (render lock, budget, sensitivity).
- :mod:`.markets`: sweeps over markets (every point tuned to pass several markets).
- :mod:`.feasibility`: the ECs no ISP setting can pass at a point (no search needed).
- :mod:`.recheck`: continuation over the grid, re-checks, and each point's verdict.
- :mod:`.yields`: each design point's yield over production variation.
- :mod:`.payloads`: the typed dicts of the tasks and their results (the stored JSON).
- :mod:`.store`: ``sweep.sqlite``.
- :mod:`.run`: running or resuming a sweep.
- :mod:`.outputs`: the sweep table, CSV/JSON and the files of a sweep.
- :mod:`.tasks`: ``rvmsim batch``: one tuning run per scene, locally or on Dask.
"""

from __future__ import annotations

from .executors import (
    Executor,
    LocalExecutor,
    DaskExecutor,
    make_executor,
    task_malloc,
)
from .spec import (
    AXES,
    SweepSpec,
    RecheckSettings,
    DesignPoint,
    load_sweep,
    design_points,
    point_scene_doc,
)
from .yields import (
    YieldSettings,
    YIELD_COLUMNS,
    MAX_YIELD_SAMPLES,
    point_yield,
    yield_summary,
    yield_cells,
)
from .point import run_point
from .probes import (
    sensitivity,
    probe_sensitivity,
    SENSITIVITY_STEPS,
)
from .markets import (
    sweep_markets,
    market_ec_ids,
    market_names,
    markets_yield,
    run_markets_point,
)
from .feasibility import (
    Infeasibility,
    infeasible_ecs,
)
from .recheck import (
    VERDICTS,
    grid_index,
    grid_neighbours,
    recheck_seed,
    merge_point,
    merged_results,
)
from .store import (
    SweepStore,
)
from .run import (
    PHASES,
    phase_seconds,
    SweepResult,
    run_sweep,
    stored_sweep,
    point_task,
)
from .payloads import (
    PointTask,
    YieldTask,
    BatchTask,
    PointRun,
    PointError,
    PointResult,
    MergedPoint,
    MergedResult,
    YieldDoc,
    YieldError,
)
from .outputs import (
    Cell,
    sweep_table,
    csv_text,
    sweep_json,
    page_columns,
    point_verdict,
)
from .tasks import (
    BatchSettings,
    SceneRun,
    run_batch,
    summary_ec_ids,
    summary_table,
    write_summary,
    tune_task,
    portable_scene_doc,
)

__all__ = [
    "Executor",
    "LocalExecutor",
    "DaskExecutor",
    "make_executor",
    "task_malloc",
    "AXES",
    "SweepSpec",
    "RecheckSettings",
    "DesignPoint",
    "load_sweep",
    "design_points",
    "point_scene_doc",
    "YieldSettings",
    "YIELD_COLUMNS",
    "MAX_YIELD_SAMPLES",
    "point_yield",
    "yield_summary",
    "yield_cells",
    "run_point",
    "sensitivity",
    "probe_sensitivity",
    "SENSITIVITY_STEPS",
    "sweep_markets",
    "market_ec_ids",
    "market_names",
    "markets_yield",
    "run_markets_point",
    "Infeasibility",
    "infeasible_ecs",
    "VERDICTS",
    "grid_index",
    "grid_neighbours",
    "recheck_seed",
    "merge_point",
    "merged_results",
    "SweepStore",
    "SweepResult",
    "PHASES",
    "phase_seconds",
    "run_sweep",
    "stored_sweep",
    "point_task",
    "PointTask",
    "YieldTask",
    "BatchTask",
    "PointRun",
    "PointError",
    "PointResult",
    "MergedPoint",
    "MergedResult",
    "YieldDoc",
    "YieldError",
    "Cell",
    "sweep_table",
    "csv_text",
    "sweep_json",
    "page_columns",
    "point_verdict",
    "BatchSettings",
    "SceneRun",
    "run_batch",
    "summary_ec_ids",
    "summary_table",
    "write_summary",
    "tune_task",
    "portable_scene_doc",
]
