"""Tune one vehicle: render once (cached), search, store every candidate, write the results.

A run lives in a folder: ``run.sqlite`` (every candidate, see :mod:`rvmsim.store`),
``run.json`` (what was run), and at the end ``top/rank_K.yaml`` (the top-M parameter sets)
and ``best/`` (the best candidate's RVM image, annotated EC image and EC table).
"""

from __future__ import annotations

import dataclasses
import json
import math
import multiprocessing as mp
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import numpy as np

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .._io import input_error_from_validation, key_lines, parse_yaml, read_text
from ..criteria.core import Criteria, load_criteria
from ..errors import RvmsimError, TuningConfigError
from ..criteria.evaluator import CandidateEvaluator
from ..isp import IspParams, OutputSpec, params_to_dict
from .search import (
    STRATEGIES,
    CmaEs,
    GridToRandom,
    ParamRange,
    RandomSearch,
    ScoredBatch,
    SearchOutcome,
    SearchSpace,
    Strategy,
    default_space,
    run_search,
    score_vectors,
)
from .store import RunStore

__all__ = ["TuningConfig", "load_tuning_config", "tune", "TuneResult", "write_results",
           "tune_task", "portable_scene_doc"]

#: Size of the RVM display image written for the best candidate (the ECs are measured at the
#: tuning config's ``output`` size).
DISPLAY_SIZE = (1280, 720)


class _Range(BaseModel):
    model_config = ConfigDict(extra="forbid")
    init: float | None = None
    range: tuple[float, float] | None = None
    step: Annotated[float, Field(gt=0)] | None = None
    points: Annotated[int, Field(ge=1, le=99)] | None = None


class _Output(BaseModel):
    model_config = ConfigDict(extra="forbid")
    size: tuple[Annotated[int, Field(ge=16, le=8192)], Annotated[int, Field(ge=16, le=8192)]] = (640, 360)
    mirror: bool = True


class _GridRandom(BaseModel):
    model_config = ConfigDict(extra="forbid")
    top_n: Annotated[int, Field(ge=1)] = 2
    trials: Annotated[int, Field(ge=0)] = 20000


class _Budget(BaseModel):
    model_config = ConfigDict(extra="forbid")
    budget: Annotated[int, Field(ge=1)] = 3000
    sigma0: Annotated[float, Field(gt=0, le=1)] = 0.3


class TuningConfig(BaseModel):
    """A tuning config file (YAML); every key optional.

    ``tuned``: the parameters to search (default: the paper's nine); ``parameters``: per
    parameter ``init``, ``range`` and coarse ``step`` (default: fitted to the camera, see
    :func:`rvmsim.search.default_space`); ``fixed``: values of untuned parameters;
    ``output``: the RVM image the ECs are measured on during tuning; strategy settings.
    """

    model_config = ConfigDict(extra="forbid")
    tuned: list[str] | None = None
    parameters: dict[str, _Range] = {}
    fixed: dict[str, float] = {}
    output: _Output = _Output()
    top_m: Annotated[int, Field(ge=1, le=1000)] = 10
    #: Candidates evaluated (and stored in one transaction) at a time.
    batch: Annotated[int, Field(ge=1, le=100000)] = 1024
    grid_random: _GridRandom = _GridRandom()
    cmaes: _Budget = _Budget(budget=8000)
    random: _Budget = _Budget(budget=2000)

    def space(self, camera) -> SearchSpace:
        names = tuple(self.tuned) if self.tuned is not None else None
        base_space = default_space(camera) if names is None else default_space(camera, names)
        ranges = []
        for r in base_space.ranges:
            o = self.parameters.get(r.name)
            if o is None:
                ranges.append(r)
                continue
            lo, hi = o.range if o.range is not None else (r.low, r.high)
            init = o.init if o.init is not None else min(max(r.init, lo), hi)
            ranges.append(ParamRange(r.name, init, lo, hi, o.step or r.step, o.points or r.points))
        base = IspParams().replace(**self.fixed) if self.fixed else IspParams()
        return SearchSpace(tuple(ranges), base)

    def output_spec(self) -> OutputSpec:
        return OutputSpec(self.output.size[0], self.output.size[1], self.output.mirror)


def load_tuning_config(path: str | Path | None) -> TuningConfig:
    if path is None:
        return TuningConfig()
    path = Path(path)
    text = read_text(path, TuningConfigError)
    data = parse_yaml(text, str(path), TuningConfigError) or {}
    if not isinstance(data, dict):
        raise TuningConfigError(str(path), "", "a tuning config must be a YAML mapping")
    try:
        cfg = TuningConfig.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, str(path), key_lines(text), TuningConfigError) from None
    unknown = set(cfg.tuned or []) | set(cfg.parameters) | set(cfg.fixed)
    unknown -= set(IspParams.names())
    if unknown:
        raise TuningConfigError(str(path), sorted(unknown)[0], "not an ISP parameter")
    return cfg


def make_strategy(name: str, space: SearchSpace, cfg: TuningConfig, seed: int,
                  budget: int | None = None) -> Strategy:
    if name == GridToRandom.name:
        trials = cfg.grid_random.trials if budget is None else budget
        return GridToRandom(space, seed=seed, top_n=cfg.grid_random.top_n, trials=trials,
                            batch=cfg.batch)
    if name == CmaEs.name:
        return CmaEs(space, seed=seed, budget=budget or cfg.cmaes.budget, sigma0=cfg.cmaes.sigma0)
    if name == RandomSearch.name:
        return RandomSearch(space, seed=seed, budget=budget or cfg.random.budget, batch=cfg.batch)
    raise RvmsimError(f"unknown strategy {name!r} (known: {', '.join(STRATEGIES)})")


# ---------------------------------------------------------------------------- evaluation
_WORKER: tuple[CandidateEvaluator, SearchSpace] | None = None


def _init_worker(evaluator: CandidateEvaluator, space: SearchSpace) -> None:
    global _WORKER
    import cv2

    cv2.setNumThreads(1)
    _WORKER = (evaluator, space)


def _work(xs: list[np.ndarray]) -> ScoredBatch:
    assert _WORKER is not None
    return score_vectors(_WORKER[0], _WORKER[1], xs)


def _chunks(n: int, workers: int, smallest: int = 8) -> list[tuple[int, int]]:
    """Guided self-scheduling: chunks of half the remaining work per worker, shrinking to
    ``smallest``, so that few large chunks keep overheads low and the small last ones keep
    the workers' finishing times close (a batch ends with its slowest chunk)."""
    out, start = [], 0
    while start < n:
        size = max(smallest, math.ceil((n - start) / (2 * workers)))
        out.append((start, min(n, start + size)))
        start += size
    return out


class BatchEvaluator:
    """Evaluates batches of candidate vectors in order, in this process or in ``workers``
    worker processes, each holding its own copy of the evaluator (the fisheye label image is
    1.2 MB).  Workers also score and serialise their candidates (:func:`score_vectors`), so
    the main process only stores them and steers the search.

    Workers are spawned, not forked: a process that has run OpenCV's thread pool or an
    OpenGL context cannot be forked safely."""

    def __init__(self, evaluator: CandidateEvaluator, space: SearchSpace, workers: int = 1):
        self.evaluator = evaluator
        self.space = space
        self.workers = max(1, workers)
        self.pool = None
        if self.workers > 1:
            ctx = mp.get_context("spawn")
            self.pool = ctx.Pool(self.workers, initializer=_init_worker,
                                 initargs=(evaluator, space))

    def __call__(self, xs: list[np.ndarray]) -> ScoredBatch:
        if self.pool is None:
            return score_vectors(self.evaluator, self.space, xs)
        parts = self.pool.map(_work, [xs[a:b] for a, b in _chunks(len(xs), self.workers)],
                              chunksize=1)
        return ScoredBatch(*([v for p in parts for v in getattr(p, f.name)]
                             for f in dataclasses.fields(ScoredBatch)))

    def close(self) -> None:
        if self.pool is not None:
            self.pool.terminate()
            self.pool.join()
            self.pool = None


# ---------------------------------------------------------------------------- the run
@dataclass(frozen=True)
class TuneResult:
    run_dir: Path
    outcome: SearchOutcome
    total: int | None


def tune(
    scene_file: str | Path,
    run_dir: str | Path,
    *,
    strategy: str = GridToRandom.name,
    config: TuningConfig | None = None,
    criteria: Criteria | None = None,
    criteria_file: str | Path | None = None,
    seed: int = 0,
    workers: int = 1,
    budget: int | None = None,
    max_time: float | None = None,
    target_score: float | None = None,
    resume: bool = False,
    progress: bool = False,
    progress_position: int = 0,
) -> TuneResult:
    """Tune the ISP for one scene; see the module docstring for what is written.

    Parameters
    ----------
    budget : int, optional
        Evaluations for ``cmaes``/``random``; for ``grid-random`` the fine trials per seed
        (T), replacing the config's value (a shortened protocol).
    resume : bool
        Continue the run in ``run_dir`` with its own settings (the other arguments that
        define the run are taken from its ``run.json``).
    progress : bool
        Show a progress bar (evaluations/s, best EC score, ETA).
    progress_position : int
        Line of that bar (``rvmsim batch`` puts its overall bar above it).
    """
    from ..render import cached_render, same_scene, scene_key
    from ..scene import load_scene

    run_dir = Path(run_dir)
    run_json = run_dir / "run.json"
    if resume:
        if not run_json.is_file():
            raise RvmsimError(f"{run_dir}: no run to resume (run.json missing)")
        saved = json.loads(run_json.read_text())
        scene_file, strategy, seed = saved["scene"], saved["strategy"], saved["seed"]
        budget, criteria_file = saved.get("budget"), saved.get("criteria_file")
        config = TuningConfig.model_validate(saved["config"])
        criteria = None
    elif (run_dir / "run.sqlite").exists():
        raise RvmsimError(f"{run_dir}: a run exists here already; use --resume to continue it")
    config = config or TuningConfig()
    if criteria is None:
        criteria = load_criteria(criteria_file)
    scene = load_scene(scene_file)
    key = scene_key(scene)
    if resume and not same_scene(saved.get("scene_key", key), scene, scene_file):
        raise RvmsimError(f"{scene_file}: the scene changed since this run started; "
                          "resuming would mix two scenes (start a new run)")
    images, _ = cached_render(scene, progress=progress)
    space = config.space(images.camera)
    strat = make_strategy(strategy, space, config, seed, budget)
    if not resume:
        run_dir.mkdir(parents=True, exist_ok=True)
        run_json.write_text(json.dumps({
            "scene": str(Path(scene_file).resolve()), "scene_key": key,
            "vehicle": scene.name, "strategy": strategy,
            "seed": seed, "budget": budget,
            "criteria_file": None if criteria_file is None else str(Path(criteria_file).resolve()),
            "config": config.model_dump(mode="json"),
        }, indent=2))
    store = RunStore(run_dir / "run.sqlite")
    store.set_meta(status="running", strategy=strategy, total=strat.total())
    evaluator = CandidateEvaluator(images.labels, config.output_spec(), criteria)
    batch_eval = BatchEvaluator(evaluator, space, workers)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=strat.total(), unit="eval", desc=f"tune {scene.name}", smoothing=0.1,
                   position=progress_position, leave=progress_position == 0)

    def on_batch(done: int, best: float, stage: str) -> None:
        if bar is not None:
            bar.update(done - bar.n)
            bar.set_postfix_str(f"best {best:.4g} [{stage}]")

    try:
        outcome = run_search(strat, batch_eval, store, max_time=max_time,
                             target_score=target_score, on_batch=on_batch)
    except KeyboardInterrupt:
        store.set_meta(status="interrupted (continue with --resume)")
        store.close()
        raise
    finally:
        batch_eval.close()
        if bar is not None:
            bar.close()
    store.set_meta(status="done" if outcome.stopped == "done" else f"stopped ({outcome.stopped})")
    write_results(run_dir, store, scene, images, config, criteria)
    store.close()
    return TuneResult(run_dir, outcome, strat.total())


def write_results(run_dir: Path, store: RunStore, scene, images, config: TuningConfig,
                  criteria: Criteria) -> None:
    """top/rank_K.yaml for the top-M, and best/: RVM image (tuning size and display size),
    annotated ECs, EC table."""
    import yaml

    from ..criteria.annotate import annotate
    from ..criteria.core import evaluate
    from .._io import write_png
    from ..isp import process

    top = store.top(config.top_m)
    if not top:
        return
    out = config.output_spec()
    (run_dir / "top").mkdir(parents=True, exist_ok=True)
    for k, rec in enumerate(top, start=1):
        doc = params_to_dict(rec.params, out)
        (run_dir / "top" / f"rank_{k}.yaml").write_text(
            f"# rank {k} of {scene.name}: EC score {rec.score:.6g} (trial {rec.idx}, {rec.stage})\n"
            + yaml.safe_dump(doc, sort_keys=False))
    best = top[0]
    color, labels = process(images.color, images.labels, best.params, out)
    result = evaluate(labels, criteria)
    write_png(run_dir / "best" / "rvm_color.png", color)
    write_png(run_dir / "best" / "rvm_labels.png", labels)
    write_png(run_dir / "best" / "ec_annotated.png", annotate(color, labels, result))
    (run_dir / "best" / "ec.json").write_text(json.dumps(
        {"vehicle": scene.name, "trial": best.idx, **result.as_dict(),
         "isp": params_to_dict(best.params, out)}, indent=2))
    (run_dir / "best" / "ec_table.txt").write_text(result.table() + "\n")
    # The same view at the display's size (the view is defined in normalised coordinates, so
    # only the pixel count changes; aspect ratios differing from 16:9 crop or extend it).
    display = OutputSpec(DISPLAY_SIZE[0], DISPLAY_SIZE[1], out.mirror)
    write_png(run_dir / "best" / "rvm_display.png",
              process(images.color, None, best.params, display)[0])


# ---------------------------------------------------------------------------- remote runs
def portable_scene_doc(scene_file: str | Path) -> dict:
    """The scene file's document with its mesh paths made absolute, so it loads from any
    folder (a task on a cluster worker writes it to a temporary file)."""
    from ..scene import absolute_mesh_paths, read_scene_document

    _, doc = read_scene_document(scene_file)  # one-line errors here, not on a worker
    absolute_mesh_paths(doc, Path(scene_file).parent)
    return doc


def tune_task(task: dict) -> dict:
    """One vehicle's tuning run as a task for :mod:`rvmsim.executors` (a cluster worker):
    the run is made in a temporary folder and returned as ``{"files": {relative path:
    bytes}}`` (or ``{"error": message}``), for the caller to write into its run folder."""
    import os
    import tempfile

    import yaml

    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    from ..criteria.core import criteria_from_text
    from ..batch.executors import task_malloc

    try:
        with tempfile.TemporaryDirectory(prefix="rvmsim-tune-") as tmp, task_malloc():
            scene_file = Path(tmp) / "scene.yaml"
            scene_file.write_text(yaml.safe_dump(task["scene"], sort_keys=False))
            criteria = (criteria_from_text(task["criteria"], "criteria")
                        if task.get("criteria") else None)
            run_dir = Path(tmp) / "run"
            res = tune(scene_file, run_dir, strategy=task["strategy"],
                       config=TuningConfig.model_validate(task["config"]), criteria=criteria,
                       seed=task["seed"], workers=task.get("workers", 1),
                       budget=task.get("budget"))
            files = {str(p.relative_to(run_dir)): p.read_bytes()
                     for p in sorted(run_dir.rglob("*")) if p.is_file()}
            return {"files": files, "evaluated": res.outcome.evaluated,
                    "replayed": res.outcome.replayed, "seconds": res.outcome.seconds}
    except RvmsimError as err:
        return {"error": str(err)}
