"""Many tasks at once: executors (local processes, Dask), design-stage sweeps, and batches of
tuning runs.

- :mod:`.executors`: where tasks run (local processes or a Dask cluster).
- :mod:`.spec`: the sweep file, its axes and design points.
- :mod:`.point`: one design point as a task (render, tune, sensitivity).
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
    DesignPoint,
    load_sweep,
    design_points,
    point_scene_doc,
)
from .point import (
    run_point,
    sensitivity,
    SENSITIVITY_STEPS,
)
from .store import (
    SweepStore,
)
from .run import (
    SweepResult,
    run_sweep,
    stored_sweep,
    point_task,
)
from .outputs import (
    sweep_table,
    csv_text,
    sweep_json,
    page_columns,
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
    "DesignPoint",
    "load_sweep",
    "design_points",
    "point_scene_doc",
    "run_point",
    "sensitivity",
    "SENSITIVITY_STEPS",
    "SweepStore",
    "SweepResult",
    "run_sweep",
    "stored_sweep",
    "point_task",
    "sweep_table",
    "csv_text",
    "sweep_json",
    "page_columns",
    "BatchSettings",
    "SceneRun",
    "run_batch",
    "summary_ec_ids",
    "summary_table",
    "write_summary",
    "tune_task",
    "portable_scene_doc",
]
