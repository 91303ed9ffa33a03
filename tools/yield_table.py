"""Table: the yield of the nominal-tuned and the robust-tuned setting of every bundled vehicle
(not a test; issue #16's table in docs/guide.md).

    PYTHONPATH=$PWD python3 tools/yield_table.py [--vehicles a,b,c,d,e,f] [--samples 200]
        [--robust-samples 16] [--seed 0] [--eval-seed S] [--budget N] [--scale 1.0]
        [--scales 1.0] [--workers 2] [--out out/yield_table] [--no-progress]

For every bundled scene ``scenes/vehicle_<letter>.yaml``:

1. nominal tuning: :func:`rvmsim.tune.tune` with the default strategy (``cmaes-solved``),
   ``--seed``, the default budget (or ``--budget``), as ``rvmsim tune SCENE`` does;
2. robust tuning: the same with ``kind=Robust(K)`` (``--robust-samples``), as
   ``rvmsim tune SCENE --robust --samples K`` does (the default aggregate, the 10 % quantile
   over the nominal image and the K samples);
3. :func:`rvmsim.robust.robustness` of both best settings on the same ``--samples`` samples
   (Sobol seed ``--eval-seed``, default ``--seed``) of the scene's ``variation`` section, at
   the tolerance scales ``--scales`` (the table needs 1x only).

It prints a markdown table (vehicle | nominal-tuned: EC score at nominal, yield with its 95 %
Wilson interval | robust-tuned: EC score at nominal, robust score, yield | what prevents
100 %: for the better setting, every failing EC with its failure rate and the tolerance axis
that drives it), the machine and each vehicle's wall times, and writes
``OUT/yield_table.json`` and ``OUT/yield_table.md``.

Everything is kept under ``--out`` and reused: the run folders (``OUT/<vehicle>/nominal-…``,
``robust-k…``; an unfinished run is resumed) with a record of each finished one
(``<run>.json``), and each setting's robustness result
(``robustness_<run>-n<samples>-e<eval seed>.json``, recomputed only when the setting,
samples, seed or scales change), so a second invocation only rebuilds the table.  The
wall times shown are those of the invocation that computed each step.

Note: the Sobol samples of one seed are a prefix sequence, so with ``--eval-seed`` equal to
``--seed`` the K tuning samples are the first K of the evaluation samples (the robust-tuned
setting has seen K/N of them); the table says so.  ``--eval-seed`` other than ``--seed``
judges both settings on fresh samples.

``--scale`` renders a fraction of each sensor (scaled scene copies under ``OUT/scenes/``, for
quick tries; the tuning output size, and so every EC's pixel ranges, stays the same).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
VEHICLES = "abcdef"


def say(msg: str) -> None:
    """A progress line (stderr: stdout holds the table)."""
    print(msg, file=sys.stderr, flush=True)


def scene_file(letter: str, scale: float, out: Path) -> Path:
    """The bundled scene of vehicle ``letter``, or at ``scale`` a copy of it with the sensor
    resampled (:meth:`rvmsim.camera.FisheyeCamera.scaled`: focal lengths and principal point
    scale, the lens stays) written under ``out/scenes/``."""
    import yaml

    from rvmsim.scene import absolute_mesh_paths, read_scene_document

    src = ROOT / "scenes" / f"vehicle_{letter}.yaml"
    if scale == 1.0:
        return src
    scene, doc = read_scene_document(src)
    absolute_mesh_paths(doc, src.parent)
    cam = scene.fisheye_camera().scaled(scale)
    doc["camera"]["image_size"] = [cam.width, cam.height]
    doc["camera"]["intrinsics"] = {"K": [[cam.fx, cam.skew * cam.fx, cam.cx],
                                         [0.0, cam.fy, cam.cy], [0.0, 0.0, 1.0]]}
    path = out / "scenes" / f"vehicle_{letter}@{scale:g}.yaml"
    text = f"# {src.name} at {scale:g} of its sensor (tools/yield_table.py)\n" + yaml.safe_dump(
        doc, sort_keys=False)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.is_file() or path.read_text() != text:  # unchanged: its runs stay resumable
        path.write_text(text)
    return path


def _check_run(run_dir: Path, want: dict[str, Any]) -> None:
    """Refuse to resume a run in ``run_dir`` made with other settings than ``want``."""
    from rvmsim.runs import open_run, run_settings

    store = open_run(run_dir)
    try:
        s = run_settings(run_dir, store)
    finally:
        store.close()
    robust = s.kind.robust
    have = {"scene": s.scene, "scene_key": s.scene_key, "strategy": s.strategy,
            "seed": s.seed, "budget": s.budget,
            "robust_samples": None if robust is None else robust.samples,
            "variation_key": None if robust is None else robust.variation_key}
    if robust is not None and robust.compensation is not None:
        have["compensation"] = robust.compensation
    if have != want:
        raise SystemExit(f"{run_dir}: holds a run with other settings ({have}, wanted {want});"
                         " delete it or give another --out")


def tuned(scene_path: Path, run_dir: Path, robust_samples: int | None,
          args: argparse.Namespace, compensation: Any = None) -> dict[str, Any]:
    """The best setting of one tuning run in ``run_dir`` (run, resumed, or read back when a
    finished run's record ``<run_dir>.json`` is there and the scene and its variation are
    as they were); ``compensation``: a robust run for the yield after end-of-line
    compensation (:class:`rvmsim.compensation.CompensationModel`)."""
    from rvmsim.isp import load_params, params_to_dict
    from rvmsim.render import scene_key
    from rvmsim.scene import load_scene
    from rvmsim.tune import Robust, RunOptions, TuneRequest, resume, tune
    from rvmsim.search import DEFAULT_STRATEGY
    from rvmsim.tune.robust import run_variations, variation_key

    scene = load_scene(scene_path)
    record = run_dir.with_name(run_dir.name + ".json")
    want = {"scene": str(scene_path.resolve()), "scene_key": scene_key(scene),
            "strategy": DEFAULT_STRATEGY, "seed": args.seed, "budget": args.budget,
            "robust_samples": robust_samples,
            "variation_key": None if robust_samples is None else variation_key(
                run_variations([scene], None))}
    if compensation is not None:
        want["compensation"] = compensation.as_dict()
    rank_1 = run_dir / "top" / "rank_1.yaml"
    if record.is_file() and rank_1.is_file():
        doc = json.loads(record.read_text())
        if doc.get("settings") == want:
            return {**doc, "reused": True}
    t0 = time.perf_counter()
    resumed = (run_dir / "run.sqlite").is_file()
    if resumed:
        _check_run(run_dir, want)
        say(f"  resuming {run_dir}")
        result = resume(run_dir, options=RunOptions(args.workers, progress=args.progress))
    else:
        say(f"  tuning into {run_dir}")
        result = tune(TuneRequest((scene_path,), DEFAULT_STRATEGY, seed=args.seed,
                                  budget=args.budget,
                                  kind=None if robust_samples is None else Robust(
                                      robust_samples, compensation=compensation)), run_dir,
                      options=RunOptions(args.workers, progress=args.progress))
    seconds = time.perf_counter() - t0
    params, output = load_params(rank_1)
    best = result.outcome.best
    robust = None
    if robust_samples is not None:
        top = json.loads((run_dir / "best" / "robust.json").read_text())
        robust = {"aggregate": top["aggregate"], **top["top"][0]}
    doc = {"settings": want, "run": str(run_dir), "isp": params_to_dict(params, output),
           "best_score": None if best is None else best.score,
           "best_passed": None if best is None else bool(best.passed),
           "evaluated": result.outcome.evaluated, "replayed": result.outcome.replayed,
           "robust": robust, "seconds": seconds, "resumed": resumed}
    record.write_text(json.dumps(doc, indent=1))
    return {**doc, "reused": False}


def yield_of(scene_path: Path, setting: dict[str, Any], path: Path,
             args: argparse.Namespace) -> dict[str, Any]:
    """:func:`rvmsim.robust.robustness` of one tuned setting (read back from ``path`` when
    it holds the result of the same scene, setting, samples, seed and scales)."""
    import yaml

    from rvmsim.isp import load_params
    from rvmsim.render import scene_key
    from rvmsim.robust import RobustnessSettings, robustness
    from rvmsim.scene import load_scene

    scene = load_scene(scene_path)
    key = {"scene_key": scene_key(scene), "isp": setting["isp"], "samples": args.samples,
           "seed": args.eval_seed, "scales": list(args.scales)}
    if path.is_file():
        doc = json.loads(path.read_text())
        if doc.get("key") == key:
            return {**doc, "reused": True}
    params_file = path.with_suffix(".params.yaml")
    params_file.write_text(yaml.safe_dump(setting["isp"], sort_keys=False))
    params, output = load_params(params_file)
    say(f"  robustness of {path.stem}: {args.samples} samples")
    t0 = time.perf_counter()
    res = robustness(scene, params, RobustnessSettings(output, samples=args.samples,
                                                       seed=args.eval_seed,
                                                       scales=tuple(args.scales)),
                     progress=args.progress)
    doc = {"key": key, "seconds": time.perf_counter() - t0, "result": res.as_dict()}
    path.write_text(json.dumps(doc, indent=1))
    return {**doc, "reused": False}


def driver_phrase(describe: str | None) -> str:
    """``roll_deg (fails at low and high: 40 % / 0 % / 38 %)`` (an
    :meth:`~rvmsim.robust.AxisEffect.describe`) as ``roll_deg: fails at low and high``."""
    if describe is None:
        return "no single axis"
    axis, _, rest = describe.partition(" (")
    return f"{axis}: {rest.rstrip(')').rsplit(': ', 1)[0]}" if rest else describe


def blockers(result: dict[str, Any]) -> list[dict[str, Any]]:
    """The enabled ECs that fail on some sample, most often failing first."""
    n = result["n"]
    out = [{"ec": e["id"], "failure_rate": e["failure_rate"],
            "driver": e["driver"] if e["n_fail"] < n else None,
            "text": f"{e['id']} ({100 * e['failure_rate']:.0f} %, "
                    + ("on every sample" if e["n_fail"] == n else driver_phrase(e["driver"]))
                    + ")"}
           for e in result["ecs"] if e["enabled"] and e["n_fail"]]
    return sorted(out, key=lambda b: -b["failure_rate"])


def vehicle_row(letter: str, args: argparse.Namespace) -> dict[str, Any]:
    """Tune vehicle ``letter`` both ways and judge both settings on the same samples."""
    from rvmsim.scene import load_scene

    t0 = time.perf_counter()
    path = scene_file(letter, args.scale, args.out)
    name = load_scene(path).name
    folder = args.out / (f"vehicle_{letter}" if args.scale == 1.0 else
                         f"vehicle_{letter}@{args.scale:g}")
    folder.mkdir(parents=True, exist_ok=True)
    budget = "" if args.budget is None else f"-b{args.budget}"
    say(f"{name} ({path})")
    nominal_run = folder / f"nominal-s{args.seed}{budget}"
    robust_run = folder / f"robust-k{args.robust_samples}-s{args.seed}{budget}"
    nominal = tuned(path, nominal_run, None, args)
    robust = tuned(path, robust_run, args.robust_samples, args)
    judged = f"-n{args.samples}-e{args.eval_seed}.json"
    y_nom = yield_of(path, nominal, folder / f"robustness_{nominal_run.name}{judged}", args)
    y_rob = yield_of(path, robust, folder / f"robustness_{robust_run.name}{judged}", args)
    r_nom, r_rob = y_nom["result"], y_rob["result"]
    better = "robust-tuned" if r_rob["yield"] >= r_nom["yield"] else "nominal-tuned"
    return {
        "vehicle": letter, "name": name, "scene": str(path),
        "nominal_tuned": _setting_summary(nominal, r_nom),
        "robust_tuned": {**_setting_summary(robust, r_rob),
                         "robust_score": robust["robust"]["robust_score"],
                         "run_nominal_score": robust["robust"]["nominal_score"],
                         "aggregate": robust["robust"]["aggregate"],
                         "tuning_samples_yield": robust["robust"]["yield"]},
        "better": better,
        "blockers": blockers(r_rob if better == "robust-tuned" else r_nom),
        "seconds": {"tune_nominal": nominal["seconds"], "tune_robust": robust["seconds"],
                    "robustness_nominal": y_nom["seconds"],
                    "robustness_robust": y_rob["seconds"]},
        "reused": {"tune_nominal": nominal["reused"], "tune_robust": robust["reused"],
                   "robustness_nominal": y_nom["reused"], "robustness_robust": y_rob["reused"]},
        "resumed": {"tune_nominal": nominal.get("resumed", False),
                    "tune_robust": robust.get("resumed", False)},
        "seconds_this_invocation": time.perf_counter() - t0,
    }


def _setting_summary(tune_doc: dict[str, Any], result: dict[str, Any]) -> dict[str, Any]:
    return {"run": tune_doc["run"], "isp": tune_doc["isp"], "best_score": tune_doc["best_score"],
            "nominal_score": result["nominal"]["ec_score"],
            "nominal_passed": result["nominal"]["passed"],
            "yield": result["yield"], "ci95": result["ci95"], "n_pass": result["n_pass"],
            "n": result["n"], "failing_ecs": {e["id"]: e["failure_rate"] for e in result["ecs"]
                                              if e["enabled"] and e["n_fail"]},
            "scale_curve": {f"{p['scale']:g}": p["yield"] for p in result["scale_curve"]}}


def _yield_text(s: dict[str, Any]) -> str:
    lo, hi = s["ci95"]
    return f"{100 * s['yield']:.1f} % ({100 * lo:.1f}–{100 * hi:.1f} %)"


def _score_text(s: dict[str, Any]) -> str:
    return f"{s['nominal_score']:.3g}" + ("" if s["nominal_passed"] else " (fails)")


def _secs(x: float) -> str:
    return f"{x:.1f}" if x < 10 else f"{x:.0f}"


def markdown(doc: dict[str, Any]) -> str:
    """The table in docs/guide.md, the notes under it, the machine and the wall times."""
    m = doc["settings"]
    agg = doc["rows"][0]["robust_tuned"]["aggregate"] if doc["rows"] else "?"
    lines = [
        f"| vehicle | nominal-tuned: EC score at nominal | yield (95 % CI) | robust-tuned "
        f"(K = {m['robust_samples']}): EC score at nominal | robust score ({agg} of nominal + "
        f"K samples) | "
        "yield (95 % CI) | what prevents 100 % (EC: failure rate, driving axis) |",
        "|---|---|---|---|---|---|---|"]
    for r in doc["rows"]:
        n, rb = r["nominal_tuned"], r["robust_tuned"]
        block = ("reaches 100 % on these samples" if not r["blockers"] else
                 f"{r['better']}: " + "; ".join(b["text"] for b in r["blockers"]))
        lines.append(f"| {r['name']} | {_score_text(n)} | {_yield_text(n)} | "
                     f"{_score_text(rb)} | {rb['robust_score']:.3g} | {_yield_text(rb)} | "
                     f"{block} |")
    budget = "default budget" if m["budget"] is None else f"budget {m['budget']}"
    lines += ["", f"{m['samples']} samples (Sobol seed {m['eval_seed']}) of each scene's "
              f"variation section at 1x its tolerances; both settings on the same samples. "
              f"Tuning: {m['strategy']}, seed {m['seed']}, "
              f"{budget}; "
              f"render scale {m['scale']:g}."]
    if m["eval_seed"] == m["seed"]:
        lines.append(f"The robust runs' {m['robust_samples']} tuning samples are the first "
                     f"{m['robust_samples']} of these {m['samples']} (same seed).")
    if len(m["scales"]) > 1:
        lines += ["", "| vehicle | nominal-tuned yield by tolerance scale | robust-tuned |",
                  "|---|---|---|"]
        for r in doc["rows"]:
            lines.append(f"| {r['name']} | " + " | ".join(", ".join(
                f"{k}x {100 * v:.0f} %" for k, v in r[s]["scale_curve"].items())
                for s in ("nominal_tuned", "robust_tuned")) + " |")
    lines += ["", f"Machine: {doc['machine']['cpu_model']}, {doc['machine']['cores']} cores, "
              f"Python {doc['machine']['python']}, {m['workers']} workers. Wall times (s; "
              "as computed; * read back this time, + the resumed part of a run only):", "",
              "| vehicle | tune nominal | tune robust | robustness nominal-tuned | "
              "robustness robust-tuned | total |", "|---|---|---|---|---|---|"]
    for r in doc["rows"]:
        t, reused, resumed = r["seconds"], r["reused"], r["resumed"]
        cells = [f"{_secs(t[k])}{'+' if resumed.get(k) else ''}{'*' if reused[k] else ''}"
                 for k in t]
        lines.append(f"| {r['name']} | " + " | ".join(cells) + f" | {_secs(sum(t.values()))} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vehicles", default=",".join(VEHICLES),
                    help="letters of the bundled vehicles, comma-separated [a,b,c,d,e,f]")
    ap.add_argument("--samples", type=int, default=200, help="evaluation samples [200]")
    ap.add_argument("--robust-samples", type=int, default=16, help="K of the robust runs [16]")
    ap.add_argument("--seed", type=int, default=0, help="tuning seed (and K samples') [0]")
    ap.add_argument("--eval-seed", type=int, default=None,
                    help="Sobol seed of the evaluation samples [--seed]")
    ap.add_argument("--budget", type=int, default=None,
                    help="tuning evaluations [the strategy's default]")
    ap.add_argument("--scale", type=float, default=1.0, help="render fraction [1.0]")
    ap.add_argument("--scales", default="1.0",
                    help="tolerance scales of the yield curve, comma-separated [1.0]")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("out/yield_table"))
    ap.add_argument("--progress", action=argparse.BooleanOptionalAction, default=True)
    args = ap.parse_args()
    letters = [v.strip().lower() for v in args.vehicles.split(",") if v.strip()]
    bad = [v for v in letters if v not in VEHICLES or len(v) != 1]
    if bad or not letters:
        ap.error(f"--vehicles: {','.join(bad) or 'none'}: give letters from {VEHICLES}")
    if not 0 < args.scale <= 1:
        ap.error("--scale: give a fraction in (0, 1]")
    args.scales = tuple(float(s) for s in args.scales.split(","))
    args.eval_seed = args.seed if args.eval_seed is None else args.eval_seed
    from rvmsim.search import DEFAULT_STRATEGY

    from rvmsim.errors import RvmsimError

    t0 = time.perf_counter()
    try:
        rows = [vehicle_row(v, args) for v in letters]
    except RvmsimError as err:
        raise SystemExit(f"yield_table: {err}") from None
    doc = {"machine": {"cpu_model": cpu_model(), "cores": os.cpu_count(),
                       "python": platform.python_version()},
           "settings": {"vehicles": letters, "samples": args.samples,
                        "robust_samples": args.robust_samples, "seed": args.seed,
                        "eval_seed": args.eval_seed, "budget": args.budget,
                        "strategy": DEFAULT_STRATEGY, "scale": args.scale,
                        "scales": list(args.scales), "workers": args.workers},
           "rows": rows, "seconds_this_invocation": time.perf_counter() - t0}
    text = markdown(doc)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "yield_table.json").write_text(json.dumps(doc, indent=1))
    (args.out / "yield_table.md").write_text(text)
    print(text, end="")
    say(f"wrote {args.out / 'yield_table.json'} and {args.out / 'yield_table.md'} "
        f"({doc['seconds_this_invocation']:.0f} s)")


if __name__ == "__main__":
    main()
