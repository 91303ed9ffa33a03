"""Benchmark: the yield after end-of-line compensation against the station's accuracy, for
every bundled vehicle's nominal-tuned setting (not a test; the compensation table of docs/guide.md, issues #25 and #41).

    PYTHONPATH=$PWD python3 tools/bench_compensation.py [--vehicles a,b,c,d,e,f]
        [--samples 400] [--seed 0] [--eval-seed 1] [--sigmas 0,0.02,0.05,0.1]
        [--mm-per-deg 10] [--edge-per-deg 3] [--budget N] [--workers 2]
        [--out out/yield_table] [--robust-samples K [--skip-nominal]] [--no-progress]

For every vehicle:

1. its nominal-tuned setting (``tools/yield_table.py``'s run folders under ``--out``: tuned
   once, then read back);
2. :func:`rvmsim.robust.robustness` without compensation and with the default compensation
   model (``law: ec-solve``) at each station accuracy σ of ``--sigmas`` (angles, degrees;
   positions ``--mm-per-deg`` × σ mm; the body's edge on the capture ``--edge-per-deg`` × σ
   px: 0.1° with 1 mm and 0.3 px, the documented default), ``--samples`` samples (Sobol seed
   ``--eval-seed``), tolerance scale 1 only, renders cached; and with ``law:
   reference-points`` (the law before #41) at the default σ, for comparison;
3. per point: the yield with its Wilson 95 % interval, the cars the station names
   infeasible, marginal (failed by the default policy), and the cars it passes that fail in
   the field (escapes); the failing ECs;
4. the σ at which the yield after compensation reaches 99 % (linear between the measured
   points; "< smallest" or "> largest" when outside them);
5. the cost: robustness with compensation (σ = the default) over robustness without, both
   with the renders cached, and the law's EC evaluations per car.

With ``--robust-samples K`` each vehicle is also tuned with ``--robust --samples K
--compensation default`` (the run folder ``OUT/<vehicle>/robust-comp-k<K>-s<seed>``) and
that setting gets a row of its own.

Prints a markdown table and the machine, and writes ``OUT/compensation.json`` (or
``compensation_<vehicles>.json`` for a subset) and the curves as a PNG beside it.
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
from yield_table import say, scene_file, tuned  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _robustness(scene: Any, params: Any, output: Any, args: argparse.Namespace,
                model: Any) -> tuple[Any, float]:
    from rvmsim.robust import RobustnessSettings, robustness

    t0 = time.perf_counter()
    r = robustness(scene, params, RobustnessSettings(output, samples=args.samples,
                                                     seed=args.eval_seed, scales=(1.0,),
                                                     compensation=model),
                   frames=False, progress=args.progress)
    return r, time.perf_counter() - t0


def sigma_for(curve: list[tuple[float, float]], target: float = 0.99) -> str:
    """The station σ (degrees) up to which the yield stays at ``target`` or above, by linear
    interpolation between the measured (σ, yield) points (sorted by σ)."""
    pts = sorted(curve)
    if pts[0][1] < target:
        return f"not even at {pts[0][0]:g}°"
    for (s0, y0), (s1, y1) in zip(pts, pts[1:]):
        if y1 < target:
            return f"{s0 + (s1 - s0) * (y0 - target) / (y0 - y1):.3f}°"
    return f"≥ {pts[-1][0]:g}°"


def _point(r: Any) -> dict[str, Any]:
    """One robustness result with compensation as a JSON-ready point of the curve."""
    c = r.compensated
    assert c is not None
    field_ok = r.evaluation.all_passed
    return {"yield": r.yield_, "ci95": list(r.ci),
            "failing_ecs": {e.id: e.failure_rate for e in r.ecs if e.enabled and e.n_fail},
            "infeasible": c.count("infeasible"), "marginal": c.count("marginal"),
            "escaped": int((c.accepted & ~field_ok).sum()),
            "out_of_range": int((~c.within_range).sum()),
            "evaluations_per_car": c.distribution()["evaluations_per_car"]}


def _vehicle(letter: str, label: str, path: Path, setting: dict[str, Any],
             sigmas: list[float], args: argparse.Namespace) -> tuple[str, dict[str, Any]]:
    """One tuned setting's yields before and after compensation, its costs."""
    import dataclasses

    import yaml

    from rvmsim.compensation import DEFAULT_COMPENSATION
    from rvmsim.isp import load_params
    from rvmsim.scene import load_scene

    params_file = args.out / letter / f"{label.split(',')[0]}.params.yaml"
    params_file.write_text(yaml.safe_dump(setting["isp"], sort_keys=False))
    params, output = load_params(params_file)
    scene = load_scene(path)
    # the first run renders what is not cached; time the second
    _robustness(scene, params, output, args, None)
    before, t_before = _robustness(scene, params, output, args, None)
    curve, after_docs, t_after = [], {}, None
    for s in sigmas:
        model = DEFAULT_COMPENSATION.with_station(s, s * args.mm_per_deg, s * args.edge_per_deg)
        r, t = _robustness(scene, params, output, args, model)
        if abs(s - DEFAULT_COMPENSATION.angle_sigma_deg) < 1e-12:
            t_after = t
        curve.append((s, r.yield_))
        after_docs[f"{s:g}"] = _point(r)
        say(f"  σ {s:g}°: {100 * r.yield_:.1f} % ({t:.1f} s)")
    points = dataclasses.replace(DEFAULT_COMPENSATION, law="reference-points")
    r_points, _ = _robustness(scene, params, output, args, points)
    return f"{letter} {label}", {
        "name": f"{scene.name}, {label}-tuned", "isp": setting["isp"],
        "best_score": setting.get("best_score"),
        "before": {"yield": before.yield_, "ci95": list(before.ci),
                   "failing_ecs": {e.id: e.failure_rate for e in before.ecs
                                   if e.enabled and e.n_fail}},
        "after": after_docs, "reference_points_law": _point(r_points),
        "sigma_for_99": sigma_for(curve),
        "seconds_without": t_before, "seconds_with_default": t_after}


def _row(d: dict[str, Any], sigmas: list[float]) -> str:
    lo, hi = d["before"]["ci95"]
    cells = []
    for s in sigmas:
        a = d["after"][f"{s:g}"]
        cells.append(f"{100 * a['yield']:.1f} % ({100 * a['ci95'][0]:.1f})")
    ref = d["reference_points_law"]
    return (f"| {d['name']} | {100 * d['before']['yield']:.1f} % ({100 * lo:.1f}–"
            f"{100 * hi:.1f}) | " + " | ".join(cells) + f" | {d['sigma_for_99']} | "
            f"{100 * ref['yield']:.1f} % |")


def plot_curves(doc: dict[str, Any], path: Path) -> None:
    """The yield after compensation against the station's σ, one line per setting (its
    yield before in the legend), as a PNG."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.4, 3.8))
    ax = fig.add_subplot()
    lows = []
    for k, (key, d) in enumerate(doc["vehicles"].items()):
        sig = sorted(float(s) for s in d["after"])
        y = [100 * d["after"][f"{s:g}"]["yield"] for s in sig]
        lows += y
        colour = f"C{k % 10}"
        name = d["name"].replace(", nominal-tuned", "")
        ax.plot(sig, y, "o-", color=colour,
                label=f"{name}: before {100 * d['before']['yield']:.0f} %")
    ax.axhline(99.0, color="red", lw=1, ls="--", label="99 %")
    ax.set_xlabel(f"station σ per angle, degrees (position {doc['mm_per_deg']:g} mm and "
                  f"edge {doc.get('edge_px_per_deg', 0):g} px per degree)")
    ax.set_ylabel("yield after compensation (%)")
    ax.set_title(f"law ec-solve; {doc['samples']} samples per point", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.set_ylim(min(90.0, min(lows) - 1.0), 100.5)
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vehicles", default="abcdef")
    ap.add_argument("--samples", type=int, default=400)
    ap.add_argument("--seed", type=int, default=0, help="tuning seed")
    ap.add_argument("--eval-seed", type=int, default=1, help="Sobol seed of the samples")
    ap.add_argument("--sigmas", default="0,0.02,0.05,0.1")
    ap.add_argument("--mm-per-deg", type=float, default=10.0)
    ap.add_argument("--edge-per-deg", type=float, default=3.0,
                    help="the body edge's σ on the capture, px per degree of station σ")
    ap.add_argument("--budget", type=int, default=None)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--robust-samples", type=int, default=None)
    ap.add_argument("--skip-nominal", action="store_true",
                    help="with --robust-samples: only the robust-tuned settings' rows")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "yield_table")
    ap.add_argument("--no-progress", dest="progress", action="store_false")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)

    from rvmsim.compensation import DEFAULT_COMPENSATION

    sigmas = [float(s) for s in args.sigmas.split(",")]
    rows, docs = [], {}
    for letter in args.vehicles.replace(",", ""):
        path = scene_file(letter, 1.0, args.out)
        say(f"vehicle {letter.upper()}")
        runs = [] if args.skip_nominal and args.robust_samples else [
            ("nominal", f"nominal-s{args.seed}", None, None)]
        if args.robust_samples:
            runs.append(("robust, compensated", f"robust-comp-k{args.robust_samples}-"
                         f"s{args.seed}", args.robust_samples, DEFAULT_COMPENSATION))
        for label, folder, k, comp in runs:
            setting = tuned(path, args.out / letter / folder, k, args, comp)
            key, doc = _vehicle(letter, label, path, setting, sigmas, args)
            docs[key] = doc
            rows.append(_row(doc, sigmas))
            say(rows[-1])
    head = ("| vehicle | before (95 % CI) | " + " | ".join(
        f"σ {s:g}° / {s * args.mm_per_deg:g} mm / {s * args.edge_per_deg:g} px" for s in sigmas)
        + " | σ for 99 % | reference-point law, default σ |")
    print(head)
    print("|" + "---|" * (4 + len(sigmas)))
    print("\n".join(rows))
    print("(after compensation, the lower Wilson 95 % bound in brackets)")
    print()
    for letter, d in docs.items():
        ratio = (d["seconds_with_default"] / d["seconds_without"]
                 if d["seconds_with_default"] else float("nan"))
        default = d["after"].get(f"{DEFAULT_COMPENSATION.angle_sigma_deg:g}", {})
        print(f"{d['name']}: robustness {d['seconds_without']:.1f} s without, "
              f"{d['seconds_with_default'] or float('nan'):.1f} s with compensation "
              f"({ratio:.2f}x); at the default σ: {default.get('infeasible')} infeasible, "
              f"{default.get('marginal')} marginal, {default.get('escaped')} escaped, "
              f"evaluations per car {default.get('evaluations_per_car')}")
    machine = f"{cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    print(f"\nmachine: {machine}; {args.samples} samples, Sobol seed {args.eval_seed}")
    name = ("compensation.json" if sorted(args.vehicles.replace(",", "")) == list("abcdef")
            and not args.robust_samples else f"compensation_{args.vehicles.replace(',', '')}"
            f"{'_k' + str(args.robust_samples) if args.robust_samples else ''}.json")
    doc = {"machine": machine, "samples": args.samples, "eval_seed": args.eval_seed,
           "sigmas_deg": sigmas, "mm_per_deg": args.mm_per_deg,
           "edge_px_per_deg": args.edge_per_deg, "vehicles": docs}
    (args.out / name).write_text(json.dumps(doc, indent=1))
    plot_curves(doc, (args.out / name).with_suffix(".png"))


if __name__ == "__main__":
    sys.exit(main())
