"""Design-stage feasibility sweep: can this camera, at this mount, with this lens, satisfy the
RVM requirements at all?

A sweep file names a base scene and the axes to vary; every combination of axis values is one
*design point*.  Each point is one task (:mod:`rvmsim.executors`): build the point's scene,
render it, tune the ISP with the chosen strategy and budget, and measure how sensitive the
tuned EC score is to each ISP parameter around the optimum.  Results stream into
``DIR/sweep.sqlite`` as they arrive, so an interrupted sweep resumes where it stopped, on either
executor, without re-running finished points.

Sweep file (YAML)::

    name: Vehicle A mount study
    base_scene: ../scenes/vehicle_a.yaml      # relative to the sweep file
    axes:                                      # in order; the table and maps follow it
      camera_height_m: [0.9, 1.0, 1.1]         # a named axis (see AXES) ...
      pitch_deg: {start: 25, stop: 40, num: 4} # ... lists or ranges (stop included) ...
      vehicle.bumper.top: [0.7, 0.8]           # ... or any scene key by its dotted path
    tune:
      strategy: cmaes                          # any strategy of `rvmsim tune`
      budget: 1500
      seed: 0
      config: {output: {size: [640, 360]}}     # a tuning config (as `rvmsim tune --config`)
    map: [camera_height_m, pitch_deg]          # the feasibility map's x and y axes
    sensitivity: true

Outputs: ``sweep.csv`` / ``sweep.json`` (one row per design point: axis values, best EC score,
pass/fail per EC, the limiting EC, the tuned parameters), ``feasibility.png`` and
``sensitivity.png``, and ``sweep.html`` with all of them.
"""

from __future__ import annotations

import copy
import csv
import hashlib
import io
import itertools
import json
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .._io import input_error_from_validation, key_lines, parse_yaml, read_text
from ..errors import RvmsimError, SweepFileError
from .executors import Executor, LocalExecutor
from ..scene.schema import absolute_mesh_paths
from ..tune import SqliteStore, json_default

__all__ = [
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

#: Named axes: name → (scene key path, how a value is written there).  Heights are positive
#: up; the camera position's y is negative up.
AXES: dict[str, str] = {
    "camera_height_m": "camera.mount.position.1 = -value",
    "lateral_offset_m": "camera.mount.position.0 = value",
    "bumper_overhang_m": "camera.mount.position.2 = -value (camera this far ahead of the "
                         "bumper's rearmost point)",
    "pitch_deg": "camera.mount.pitch_deg",
    "yaw_deg": "camera.mount.yaw_deg",
    "roll_deg": "camera.mount.roll_deg",
    "focal_length_px": "camera.intrinsics fx = value, fy keeping the base fy/fx, same centre",
    "horizontal_fov_deg": "camera.intrinsics = {horizontal_fov_deg: value}",
    "lens_fov_deg": "camera.lens.fov_deg",
    "output_size": "the tuning config's output.size ([W, H]): the RVM image the ECs see",
}


# ---------------------------------------------------------------------------- the file
class _Range(BaseModel):
    model_config = ConfigDict(extra="forbid")
    start: float
    stop: float
    num: int | None = Field(default=None, ge=1, le=1000)
    step: float | None = Field(default=None, gt=0)


class _Tune(BaseModel):
    model_config = ConfigDict(extra="forbid")
    strategy: str = "cmaes"
    budget: int | None = Field(default=1500, ge=1)
    seed: int = 0
    config: dict[str, Any] = {}
    criteria: str | None = None


class _SweepFile(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = "sweep"
    base_scene: str
    axes: dict[str, Union[list[Any], _Range]] = Field(min_length=1)
    tune: _Tune = _Tune()
    map: tuple[str, str] | None = None
    sensitivity: bool = True


@dataclass(frozen=True)
class SweepSpec:
    """A loaded sweep file.  ``axes`` keeps the file's order; every value list is expanded."""

    name: str
    source: str
    base_scene: Path
    base_doc: dict
    axes: tuple[tuple[str, tuple[Any, ...]], ...]
    strategy: str
    budget: int | None
    seed: int
    config: dict
    criteria_doc: str | None
    map_axes: tuple[str, str] | None
    sensitivity: bool

    def fingerprint(self) -> str:
        """Hash of what a design point's result depends on besides its axis values."""
        h = hashlib.sha256()
        h.update(json.dumps([self.base_doc, self.strategy, self.budget, self.seed, self.config,
                             self.criteria_doc, self.sensitivity], sort_keys=True,
                            default=str).encode())
        for path in absolute_mesh_paths(copy.deepcopy(self.base_doc), self.base_scene.parent):
            h.update(path.read_bytes() if path.is_file() else b"?")
        return h.hexdigest()[:20]


def _expand(name: str, v: Any, where: str) -> tuple[Any, ...]:
    if isinstance(v, _Range):
        if (v.num is None) == (v.step is None):
            raise RvmsimError(f"{where}: axes.{name}: give a range either num or step")
        if v.num is not None:
            vals = np.linspace(v.start, v.stop, v.num)
        else:
            n = int(math.floor((v.stop - v.start) / v.step + 1e-9)) + 1
            if n < 1 or n > 1000:
                raise RvmsimError(f"{where}: axes.{name}: the range gives {n} values")
            vals = v.start + v.step * np.arange(n)
        return tuple(round(float(x), 10) for x in vals)
    if not v:
        raise RvmsimError(f"{where}: axes.{name}: no values")
    return tuple(v)


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file (one-line errors naming the file and key)."""
    from ..scene.schema import read_scene_document

    path = Path(path)
    text = read_text(path, SweepFileError)
    data = parse_yaml(text, str(path), SweepFileError)
    if not isinstance(data, dict):
        raise SweepFileError(str(path), "", "a sweep file must be a YAML mapping")
    try:
        f = _SweepFile.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, str(path), key_lines(text), SweepFileError) from None
    base = Path(f.base_scene)
    base = base if base.is_absolute() else (path.parent / base).resolve()
    if not base.is_file():
        raise RvmsimError(f"{path}: base_scene: scene file not found: {base}")
    _, base_doc = read_scene_document(base)
    axes = tuple((name, _expand(name, v, str(path))) for name, v in f.axes.items())
    from ..tune import STRATEGIES

    if f.tune.strategy not in STRATEGIES:
        raise RvmsimError(f"{path}: tune.strategy: {f.tune.strategy!r} is not one of "
                          f"{', '.join(STRATEGIES)}")
    from ..tune import TuningConfig

    try:
        TuningConfig.model_validate(f.tune.config)
    except ValidationError as err:
        first = err.errors()[0]
        loc = ".".join(str(x) for x in first["loc"])
        raise RvmsimError(f"{path}: tune.config.{loc}: {first['msg']}") from None
    criteria_doc = None
    if f.tune.criteria is not None:
        cpath = Path(f.tune.criteria)
        cpath = cpath if cpath.is_absolute() else (path.parent / cpath).resolve()
        criteria_doc = read_text(cpath)
    names = [a for a, _ in axes]
    if f.map is not None and not set(f.map) <= set(names):
        raise RvmsimError(f"{path}: map: {list(f.map)} must name two of the axes {names}")
    spec = SweepSpec(name=f.name, source=str(path), base_scene=base, base_doc=base_doc,
                     axes=axes, strategy=f.tune.strategy, budget=f.tune.budget,
                     seed=f.tune.seed, config=f.tune.config, criteria_doc=criteria_doc,
                     map_axes=f.map, sensitivity=f.sensitivity)
    # Every point's scene must load: check them all now, not in a worker an hour later.
    for point in design_points(spec):
        point_scene_doc(spec, point.values)
    return spec


# ---------------------------------------------------------------------------- points
@dataclass(frozen=True)
class DesignPoint:
    """One combination of axis values; ``key`` identifies it across runs (its values)."""

    index: int
    values: tuple[tuple[str, Any], ...]

    @property
    def key(self) -> str:
        return json.dumps([[n, v] for n, v in self.values], separators=(",", ":"))

    @property
    def task_key(self) -> str:
        return hashlib.sha256(self.key.encode()).hexdigest()[:16]


def design_points(spec: SweepSpec) -> list[DesignPoint]:
    """Every combination, the first axis varying slowest."""
    names = [n for n, _ in spec.axes]
    return [DesignPoint(i, tuple(zip(names, combo)))
            for i, combo in enumerate(itertools.product(*(v for _, v in spec.axes)))]


def _set_path(doc: dict, path: str, value: Any, where: str) -> None:
    keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split(".")]
    node: Any = doc
    for k in keys[:-1]:
        try:
            node = node[k]
        except (KeyError, IndexError, TypeError):
            raise RvmsimError(f"{where}: axes.{path}: the base scene has no key "
                              f"{'.'.join(str(x) for x in keys)}") from None
    last = keys[-1]
    if isinstance(node, list):
        if not isinstance(last, int) or last >= len(node):
            raise RvmsimError(f"{where}: axes.{path}: index out of range")
        node[last] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        raise RvmsimError(f"{where}: axes.{path}: cannot set a key inside a {type(node).__name__}")


def point_scene_doc(spec: SweepSpec, values: tuple[tuple[str, Any], ...]) -> tuple[dict, dict]:
    """(scene document, tuning config document) of one design point.  Mesh paths become
    absolute, so the document loads from anywhere."""
    from ..scene.schema import scene_from_dict

    doc = copy.deepcopy(spec.base_doc)
    config = copy.deepcopy(spec.config)
    base_dir = spec.base_scene.parent
    absolute_mesh_paths(doc, base_dir)
    where = spec.source
    base_scene = None
    for name, value in values:
        mount = doc.setdefault("camera", {}).setdefault("mount", {})
        if name in ("camera_height_m", "lateral_offset_m", "bumper_overhang_m"):
            pos = list(mount.get("position", [0.0, 0.0, 0.0]))
            i, sign = {"camera_height_m": (1, -1), "lateral_offset_m": (0, 1),
                       "bumper_overhang_m": (2, -1)}[name]
            pos[i] = sign * float(value)
            mount["position"] = pos
        elif name in ("pitch_deg", "yaw_deg", "roll_deg"):
            mount[name] = float(value)
        elif name == "lens_fov_deg":
            doc["camera"].setdefault("lens", {})["fov_deg"] = float(value)
        elif name == "horizontal_fov_deg":
            doc["camera"]["intrinsics"] = {"horizontal_fov_deg": float(value)}
        elif name == "focal_length_px":
            if base_scene is None:
                base_scene = scene_from_dict(spec.base_doc, base_dir=base_dir,
                                             source=str(spec.base_scene))
            w, h = base_scene.camera.image_size
            fx, fy, cx, cy, skew = base_scene.camera.intrinsics.resolve(w, h)
            doc["camera"]["intrinsics"] = {"fx": float(value), "fy": float(value) * fy / fx,
                                           "cx": cx, "cy": cy, "skew": skew}
        elif name == "output_size":
            if not (isinstance(value, list) and len(value) == 2):
                raise RvmsimError(f"{where}: axes.output_size: values are [W, H], got {value!r}")
            config.setdefault("output", {})["size"] = list(value)
        elif "." in name:
            _set_path(doc, name, value, where)
        else:
            raise RvmsimError(f"{where}: axes.{name}: unknown axis (named axes: "
                              f"{', '.join(AXES)}; or a scene key path like "
                              "vehicle.bumper.top)")
    try:
        scene_from_dict(doc, base_dir=base_dir, source=f"{where} [{_label(values)}]")
    except RvmsimError as err:
        raise RvmsimError(f"{where}: design point {_label(values)}: {err}") from None
    return doc, config


def _label(values: tuple[tuple[str, Any], ...]) -> str:
    return ", ".join(f"{n}={v}" for n, v in values)


# ---------------------------------------------------------------------------- one point
_RENDER_LOCK = threading.Lock()


def run_point(task: dict) -> dict:
    """Render, tune and probe one design point (runs in a worker; no files but the render
    cache).  Returns a JSON-ready dict; a problem with the point is returned as ``error``."""
    from .executors import task_malloc

    with task_malloc():
        return _run_point(task)


def _run_point(task: dict) -> dict:
    import os

    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from ..render.cache import cached_render
    from ..criteria.core import criteria_from_text, default_criteria
    from ..criteria.evaluator import CandidateEvaluator
    from ..scene.schema import scene_from_dict
    from ..tune import RunStore, TuningConfig, make_strategy, run_search, score_vectors

    t0 = time.perf_counter()
    try:
        scene = scene_from_dict(task["scene"], source=task["label"])
        config = TuningConfig.model_validate(task["config"])
        criteria = (criteria_from_text(task["criteria"], "sweep criteria")
                    if task.get("criteria") else default_criteria())
        # One render at a time per process: a Dask worker with several threads would
        # otherwise open several OpenGL contexts at once.
        with _RENDER_LOCK:
            images, _ = cached_render(scene)
        space = config.space(images.camera)
        strat = make_strategy(task["strategy"], space, config, task["seed"], task["budget"])
        evaluator = CandidateEvaluator(images.labels, config.output_spec(), criteria)
        store = RunStore(":memory:")
        outcome = run_search(strat, lambda xs: score_vectors(evaluator, space, xs), store)
        best = store.top(1)[0]
        n_eval = store.count()
        store.close()
        result = {
            "score": best.score,
            "passed": bool(best.passed),
            "ecs": {ec: o.as_dict() for ec, o in best.ecs.items()},
            "params": {n: getattr(best.params, n) for n in best.params.names()},
            "tuned": list(space.names),
            "evaluations": n_eval,
            "stopped": outcome.stopped,
        }
        failing = [(v["score"], ec) for ec, v in result["ecs"].items()
                   if not v["passed"] and criteria.items[ec].enabled]
        result["limiting_ec"] = min(failing)[1] if failing else None
        if task.get("sensitivity", True):
            result["sensitivity"] = sensitivity(evaluator, space, best.params)
        result["seconds"] = time.perf_counter() - t0
        return result
    except RvmsimError as err:
        return {"error": str(err), "seconds": time.perf_counter() - t0}


#: Parameter offsets (fractions of its search range) the sensitivity is probed at.
SENSITIVITY_STEPS = (-0.1, -0.05, -0.02, 0.02, 0.05, 0.1)


def sensitivity(evaluator: Any, space: Any, best: Any) -> dict:
    """EC score with each tuned parameter moved off the optimum by ±2, 5, 10 % of its range
    (others at the optimum).  ``drop_5pct`` is 1 − (mean score at ±5 %) / optimum score: 0 if
    the parameter does not matter there, 1 if a small change loses everything."""
    from ..tune import score_vectors

    x0 = space.vector(best)
    lo, hi = space.low, space.high
    xs, meta = [x0.copy()], []
    for i, name in enumerate(space.names):
        for f in SENSITIVITY_STEPS:
            x = x0.copy()
            x[i] = x0[i] + f * (hi[i] - lo[i])
            if lo[i] - 1e-12 <= x[i] <= hi[i] + 1e-12:
                xs.append(x)
                meta.append((name, f))
    scores = score_vectors(evaluator, space, xs).score
    s0 = scores[0]
    out: dict[str, Any] = {"optimum": s0, "steps": list(SENSITIVITY_STEPS), "params": {}}
    for name in space.names:
        pts = {f: s for (n, f), s in zip(meta, scores[1:]) if n == name}
        at5 = [pts[f] for f in (-0.05, 0.05) if f in pts]
        drop = (1.0 - float(np.mean(at5)) / s0) if (at5 and s0 > 0) else None
        out["params"][name] = {"scores": [pts.get(f) for f in SENSITIVITY_STEPS],
                               "drop_5pct": drop}
    return out


# ---------------------------------------------------------------------------- the store
class SweepStore(SqliteStore):
    """``sweep.sqlite``: the sweep's settings (meta) and every finished design point (JSON)."""

    def __init__(self, path: str | Path):
        super().__init__(path, "CREATE TABLE IF NOT EXISTS points (key TEXT PRIMARY KEY, "
                               "idx INTEGER, values_json TEXT NOT NULL, result TEXT NOT NULL, "
                               "session INTEGER NOT NULL, finished REAL NOT NULL);", "sweep")

    def add(self, point: DesignPoint, result: dict, session: int) -> None:
        with self.db:
            self.db.execute("INSERT OR REPLACE INTO points VALUES (?, ?, ?, ?, ?, ?)",
                            (point.key, point.index, json.dumps(point.values),
                             json.dumps(result), session, time.time()))

    def done(self) -> dict[str, dict]:
        """Finished points (errors included) by key."""
        return {k: json.loads(r) for k, r in self.db.execute("SELECT key, result FROM points")}


# ---------------------------------------------------------------------------- the sweep
@dataclass(frozen=True)
class SweepResult:
    spec: SweepSpec
    points: list[DesignPoint]
    results: dict[str, dict]  # by point key
    ran: int  # points computed in this session
    out_dir: Path


def run_sweep(spec: SweepSpec, out_dir: str | Path, *, executor: Executor | None = None,
              force: bool = False, progress: bool = False,
              on_result: Callable[[DesignPoint, dict], None] | None = None) -> SweepResult:
    """Run (or resume) a sweep into ``out_dir``.

    Finished points in ``out_dir/sweep.sqlite`` are kept; the rest run on ``executor``
    (default: this process).  A sweep whose settings changed (base scene, tuning, mesh
    files) refuses to resume unless ``force`` (which starts over).
    """
    out_dir = Path(out_dir)
    db = out_dir / "sweep.sqlite"
    if force and db.exists():
        for suffix in ("", "-wal", "-shm"):
            Path(str(db) + suffix).unlink(missing_ok=True)
    store = SweepStore(db)
    meta = store.meta()
    fp = spec.fingerprint()
    if meta and meta.get("fingerprint") != fp:
        store.close()
        raise RvmsimError(f"{out_dir}: this sweep's settings or base scene changed since it "
                          "started (results would mix); use --force to start over")
    session = int(meta.get("sessions", 0)) + 1
    store.set_meta(fingerprint=fp, name=spec.name, source=spec.source, sessions=session,
                   axes=[[n, list(v)] for n, v in spec.axes])
    points = design_points(spec)
    done = store.done()
    todo = {p.task_key: p for p in points if p.key not in done}
    tasks = {}
    for p in todo.values():
        doc, config = point_scene_doc(spec, p.values)
        tasks[p.task_key] = {"scene": doc, "config": config, "label": _label(p.values),
                             "strategy": spec.strategy, "budget": spec.budget,
                             "seed": spec.seed, "criteria": spec.criteria_doc,
                             "sensitivity": spec.sensitivity}
    bar = None
    if progress and tasks:
        from tqdm import tqdm

        bar = tqdm(total=len(points), initial=len(points) - len(tasks), unit="point",
                   desc=f"sweep {spec.name}")
    executor = executor or LocalExecutor(1)
    ran = 0
    try:
        for task_key, result in executor.run(run_point, tasks):
            point = todo[task_key]
            store.add(point, result, session)
            done[point.key] = result
            ran += 1
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(_label(point.values))
            if on_result is not None:
                on_result(point, result)
    finally:
        if bar is not None:
            bar.close()
        store.close()
    return SweepResult(spec, points, done, ran, out_dir)


# ---------------------------------------------------------------------------- outputs
def sweep_table(spec: SweepSpec, points: list[DesignPoint], results: dict[str, dict]
                ) -> tuple[list[str], list[list[Any]]]:
    """(header, rows): one row per design point, in point order.  Deterministic content
    only (no timings), so the same sweep gives the same table on any executor."""
    from ..criteria.core import EC_IDS
    from ..isp.core import IspParams

    names = [n for n, _ in spec.axes]
    header = ["point", *names, "ec_score", "passed", "limiting_ec",
              *[f"ec_{e}" for e in EC_IDS], *IspParams.names(), "evaluations", "error"]
    rows = []
    for p in points:
        r = results.get(p.key)
        vals = [json.dumps(v) if isinstance(v, list) else v for _, v in p.values]
        if r is None or "error" in r:
            rows.append([p.index, *vals, None, None, None, *[None] * len(EC_IDS),
                         *[None] * len(IspParams.names()), None,
                         "not run" if r is None else r["error"]])
            continue
        rows.append([p.index, *vals, r["score"], r["passed"], r["limiting_ec"],
                     *["pass" if r["ecs"][e]["passed"] else "FAIL" for e in EC_IDS],
                     *[r["params"][n] for n in IspParams.names()], r["evaluations"], ""])
    return header, rows


def _csv_text(header: list[str], rows: list[list[Any]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow(["" if v is None else (repr(v) if isinstance(v, float) else v) for v in row])
    return buf.getvalue()


def _map_grid(spec: SweepSpec, points: list[DesignPoint], results: dict[str, dict]):
    """Best score, pass and limiting EC on the map's grid, best over the other axes."""
    axes = dict(spec.axes)
    if spec.map_axes is not None:
        xa, ya = spec.map_axes
    else:
        multi = [n for n, v in spec.axes if len(v) > 1] or [spec.axes[0][0]]
        xa = multi[0]
        ya = multi[1] if len(multi) > 1 else None
    xs = list(axes[xa])
    ys = list(axes[ya]) if ya is not None else [None]
    score = np.full((len(ys), len(xs)), np.nan)
    passed = np.zeros((len(ys), len(xs)), bool)
    limiting = np.full((len(ys), len(xs)), "", dtype=object)
    for p in points:
        r = results.get(p.key)
        if r is None or "error" in r:
            continue
        v = dict(p.values)
        i = ys.index(v[ya]) if ya is not None else 0
        j = xs.index(v[xa])
        if np.isnan(score[i, j]) or r["score"] > score[i, j] or (r["passed"] and not passed[i, j]):
            score[i, j] = r["score"]
            passed[i, j] = r["passed"]
            limiting[i, j] = r["limiting_ec"] or ""
    others = [n for n, v in spec.axes if n not in (xa, ya) and len(v) > 1]
    return xa, ya, xs, ys, score, passed, limiting, others


def feasibility_png(spec: SweepSpec, points: list[DesignPoint], results: dict[str, dict]) -> bytes:
    """Heat map of the best EC score over the map's two axes, the pass region outlined in
    black, and the limiting EC written in every failing cell."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from ..report.page import figure_png

    xa, ya, xs, ys, score, passed, limiting, others = _map_grid(spec, points, results)
    fig = Figure(figsize=(1.6 + 1.1 * len(xs), 1.4 + 0.8 * len(ys)))
    ax = fig.add_subplot(111)
    im = ax.imshow(score, origin="lower", cmap="viridis", vmin=0.0, vmax=1.0, aspect="auto")
    fig.colorbar(im, ax=ax, label="best EC score")
    for i in range(len(ys)):
        for j in range(len(xs)):
            if np.isnan(score[i, j]):
                txt = "—"
            elif passed[i, j]:
                txt = f"{score[i, j]:.2f}\npass"
            else:
                txt = f"{score[i, j]:.2g}\n{limiting[i, j]}"
            ax.text(j, i, txt, ha="center", va="center", fontsize=8,
                    color="white" if (np.isnan(score[i, j]) or score[i, j] < 0.5) else "black")
            if passed[i, j]:
                for di, dj, seg in ((1, 0, ([j - .5, j + .5], [i + .5, i + .5])),
                                    (-1, 0, ([j - .5, j + .5], [i - .5, i - .5])),
                                    (0, 1, ([j + .5, j + .5], [i - .5, i + .5])),
                                    (0, -1, ([j - .5, j - .5], [i - .5, i + .5]))):
                    ni, nj = i + di, j + dj
                    inside = 0 <= ni < len(ys) and 0 <= nj < len(xs) and passed[ni, nj]
                    if not inside:
                        ax.plot(*seg, color="black", linewidth=2.5)
    ax.set_xticks(range(len(xs)), [str(x) for x in xs])
    ax.set_xlabel(xa)
    if ya is not None:
        ax.set_yticks(range(len(ys)), [str(y) for y in ys])
        ax.set_ylabel(ya)
    else:
        ax.set_yticks([])
    title = "feasibility: pass region outlined; failing cells name the limiting EC"
    if others:
        title += f"\n(best over {', '.join(others)})"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return figure_png(fig)


def sensitivity_png(points: list[DesignPoint], results: dict[str, dict]) -> bytes | None:
    """Per ISP parameter: the relative EC score drop at ±5 % of its range around each design
    point's optimum (median and range over the points), and the score curves of the best
    point."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from ..report.page import figure_png

    rs = [results[p.key] for p in points if p.key in results and "sensitivity" in results[p.key]
          and results[p.key]["score"] > 0]
    if not rs:
        return None
    if any(r["passed"] for r in rs):  # where the design works is where tuning matters
        rs = [r for r in rs if r["passed"]]
    names = list(rs[0]["sensitivity"]["params"])
    drops = np.array([[r["sensitivity"]["params"][n]["drop_5pct"] or 0.0 for n in names]
                      for r in rs])
    best = max(rs, key=lambda r: r["score"])
    fig = Figure(figsize=(10, 3.8))
    ax = fig.add_subplot(121)
    med = np.median(drops, axis=0)
    order = np.argsort(-med)
    ax.barh([names[k] for k in order][::-1], med[order][::-1], color="#4a7bb7",
            xerr=None)
    ax.scatter(drops.max(axis=0)[order][::-1], range(len(names)), marker="|", color="black",
               label="max over points")
    ax.set_xlabel("EC score drop at ±5 % of range (median; < 0: a better point is near,\n"
                  "the tuning budget was short)", fontsize=8)
    ax.legend(fontsize=8)
    ax2 = fig.add_subplot(122)
    steps = best["sensitivity"]["steps"]
    xs = [*steps[:len(steps) // 2], 0.0, *steps[len(steps) // 2:]]
    for n in names:
        sc = best["sensitivity"]["params"][n]["scores"]
        ys = [*sc[:len(steps) // 2], best["sensitivity"]["optimum"], *sc[len(steps) // 2:]]
        ax2.plot([100 * x for x, y in zip(xs, ys) if y is not None],
                 [y for y in ys if y is not None], marker=".", label=n)
    ax2.set_xlabel("offset from the optimum, % of the parameter's range")
    ax2.set_ylabel("EC score (best design point)")
    ax2.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return figure_png(fig)


def write_sweep_outputs(res: SweepResult) -> list[Path]:
    """sweep.csv, sweep.json, feasibility.png, sensitivity.png and sweep.html."""
    from ..report.page import data_uri, escape, page

    out = res.out_dir
    header, rows = sweep_table(res.spec, res.points, res.results)
    written = []
    try:
        (out / "sweep.csv").write_text(_csv_text(header, rows))
        doc = {"name": res.spec.name, "sweep_file": res.spec.source,
               "base_scene": str(res.spec.base_scene), "axes": [[n, list(v)] for n, v in
                                                                 res.spec.axes],
               "strategy": res.spec.strategy, "budget": res.spec.budget, "seed": res.spec.seed,
               "points": [{"index": p.index, "values": dict(p.values),
                           **res.results.get(p.key, {"error": "not run"})}
                          for p in res.points]}
        (out / "sweep.json").write_text(json.dumps(doc, indent=1, default=json_default))
        written += [out / "sweep.csv", out / "sweep.json"]
        feas = feasibility_png(res.spec, res.points, res.results)
        (out / "feasibility.png").write_bytes(feas)
        written.append(out / "feasibility.png")
        sens = sensitivity_png(res.points, res.results) if res.spec.sensitivity else None
        if sens is not None:
            (out / "sensitivity.png").write_bytes(sens)
            written.append(out / "sensitivity.png")
        n_pass = sum(1 for r in res.results.values() if r.get("passed"))
        table = "".join(
            "<tr>" + "".join(
                f'<td class="{_cell_class(v)}">'
                f"{escape('' if v is None else (f'{v:.4g}' if isinstance(v, float) else v))}</td>"
                for v in row[:len(res.spec.axes) + 4 + 11]) + "</tr>"
            for row in rows)
        head = "".join(f"<th>{escape(h)}</th>" for h in header[:len(res.spec.axes) + 4 + 11])
        html = page(f"Sweep: {res.spec.name}", f"""
<h1>Feasibility sweep: {escape(res.spec.name)}</h1>
<p>Base scene {escape(res.spec.base_scene)}; {len(res.points)} design points
({escape(' × '.join(f'{len(v)} {n}' for n, v in res.spec.axes))}); tuning: {escape(res.spec.strategy)},
budget {escape(res.spec.budget)}, seed {escape(res.spec.seed)}. {n_pass} of {len(res.results)} finished
points pass every EC.</p>
<h2>Feasibility map</h2><img src="{data_uri(feas)}" alt="feasibility map">
{'' if sens is None else f'<h2>Sensitivity to the ISP parameters around the optimum</h2><img src="{data_uri(sens)}" alt="sensitivity">'}
<h2>Design points</h2><p>Tuned parameters per point: sweep.csv.</p>
<table><tr>{head}</tr>{table}</table>
""")
        (out / "sweep.html").write_text(html)
        written.append(out / "sweep.html")
    except OSError as err:
        raise RvmsimError(f"{out}: cannot write sweep outputs ({err.strerror or err})") from None
    return written


def _cell_class(v: Any) -> str:
    """Table cell colour class (the report's CSS): pass/True green, FAIL/False red, anything
    else plain."""
    if v == "pass" or v is True:
        return "pass"
    if v == "FAIL" or v is False:
        return "fail"
    return ""


