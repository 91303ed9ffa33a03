"""Profile: where one tuning candidate's time goes (not a test).

    python tools/profile_candidate.py [scenes/vehicle_a.yaml] [--candidates 3000]

Takes the paper protocol's candidates (a random draw from its 3⁹ coarse grid, and as many
fine-stage candidates: uniform draws one grid step around the grid's centre), from a warm
render cache, and scores them in this process as a tuning worker does
(:class:`rvmsim.tune.loop.VectorScorer`, batches of 256), under ``cProfile``.  Prints the
machine, the CPU time per candidate without the profiler, and the profiled time split into
the stages of a candidate:

``map``       the ISP map's node grid (:func:`rvmsim.isp.map_nodes`, with its error estimate)
``windows``   where each label group can appear (``node_lookup``, ``windows_at``, merging)
``remap``     the windows' maps (``cv2.resize`` of the nodes) and label pixels (``cv2.remap``)
``ECs``       the measure functions, without the remaps they ask for
``scoring``   sigmoid scores, objective, JSON of the parameters and EC columns
``other``     the rest (parameter vectors, the loop)
``IPC``       pickling a batch's results as a worker sends them (timed separately)
``storage``   writing the batch to a run store (timed separately)

Each stage is the cumulative profiled time of the functions that make it; ``cProfile`` slows
Python code more than OpenCV's, so the shares overstate the Python stages somewhat.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pickle
import platform
import pstats
import tempfile
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402
from _bench_common import cpu_model, protocol_candidates  # noqa: E402

from rvmsim.criteria import default_criteria  # noqa: E402
from rvmsim.render import cached_render  # noqa: E402
from rvmsim.runs import RunStore  # noqa: E402
from rvmsim.scene import load_scene  # noqa: E402
from rvmsim.tune import candidate_evaluator, solver_for
from rvmsim.search import TuningConfig, make_strategy
from rvmsim.tune.loop import VectorScorer  # noqa: E402

_BATCH = 256

#: Each stage as the cumulative time of the functions that make it (file suffix, name);
#: ``ECs`` is ``measure_ecs`` without the remaps it asks for.
_CUMULATIVE = {
    "map": [("isp/map.py", "map_nodes")],
    "windows": [("pipeline/candidate.py", "windows"), ("pipeline/candidate.py", "merge_windows")],
    "remap": [("pipeline/candidate.py", "remap_labels")],
    "ECs": [("criteria/measure.py", "measure_ecs")],
    "scoring": [("tune/objective.py", "score_values"), ("runs/records.py", "params_json")],
}


def _cumulative(stats: dict, keys: list[tuple[str, str]]) -> float:
    return sum(v[3] for (file, _, name), v in stats.items()
               if any(file.endswith(suffix) and name == fname for suffix, fname in keys))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default="scenes/vehicle_a.yaml")
    ap.add_argument("--candidates", type=int, default=3000)
    args = ap.parse_args()
    import cv2

    cv2.setNumThreads(1)
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}")
    images, _ = cached_render(load_scene(args.scene))
    config = TuningConfig()
    evaluator = candidate_evaluator(images, config, default_criteria())
    space = config.space(images.camera)
    strat = make_strategy("grid-random", space, config, 0, 2000)
    scorer = VectorScorer(evaluator, space, solver_for(strat, evaluator), strat.objective)
    xs = protocol_candidates(space, config, args.candidates)
    batches = [xs[a : a + _BATCH] for a in range(0, len(xs), _BATCH)]
    scorer(batches[0][:32])  # warm caches
    t = time.process_time()
    results = [scorer(b) for b in batches]
    cpu_ms = (time.process_time() - t) / len(xs) * 1e3
    print(f"scene {args.scene}: {len(xs)} candidates, RVM {evaluator.output.width}x"
          f"{evaluator.output.height}: {cpu_ms:.3f} ms CPU per candidate "
          f"({1e3 / cpu_ms:.0f} candidates/s in one process)")
    prof = cProfile.Profile()
    prof.enable()
    for b in batches:
        scorer(b)
    prof.disable()
    stats = pstats.Stats(prof).stats  # type: ignore[attr-defined]
    total = _cumulative(stats, [("tune/loop.py", "__call__")])
    shares = {stage: _cumulative(stats, keys) for stage, keys in _CUMULATIVE.items()}
    shares["ECs"] -= shares["remap"]
    shares["other"] = total - sum(shares.values())
    t = time.process_time()
    blobs = [pickle.dumps(r) for r in results]
    [pickle.loads(b) for b in blobs]
    ipc = (time.process_time() - t) / len(xs) * 1e3
    with tempfile.TemporaryDirectory() as tmp:
        store = RunStore(Path(tmp) / "run.sqlite")
        t = time.process_time()
        idx = 0
        for r in results:
            rows = [(idx + i, "fine", pj, s, o, int(ok), ej) for i, (pj, s, o, ok, ej) in
                    enumerate(zip(r.params_json, r.score, r.objective, r.passed, r.ec_json))]
            store.add_rows(rows)
            idx += len(rows)
        storage = (time.process_time() - t) / len(xs) * 1e3
        store.close()
    per = total / len(xs) * 1e3
    print(f"profiled: {per:.3f} ms per candidate")
    for stage, s in shares.items():
        print(f"  {stage:8s} {s / total:6.1%}  {s / len(xs) * 1e3:.3f} ms")
    print(f"  IPC      (pickle + unpickle of the results, main and worker) {ipc:.3f} ms, "
          f"{ipc / cpu_ms:.1%} of a candidate")
    print(f"  storage  (main process) {storage:.3f} ms, {storage / cpu_ms:.1%} of a candidate")


if __name__ == "__main__":
    main()
