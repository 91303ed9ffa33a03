"""Tune the bundled vehicles with the criteria set ``fmvss111-full`` and print the table in docs/guide.md
(not a test): per vehicle, whether the best setting passes all fourteen ECs, and for those
that do not, which EC fails and why, with its values.

    python tools/criteria_table.py                       # the six vehicles, full size
    python tools/criteria_table.py --scale 0.25 --budget 300 --vehicles a

Each vehicle is tuned with ``rvmsim tune --criteria fmvss111-full`` (the default strategy,
seed 0, the default budget unless ``--budget``) into ``OUT/<vehicle>``; ``--scale`` tunes a
copy of the scene whose sensor is that fraction of the real one (a quick look: the
magnification of EC 6-1 is per px of that smaller sensor).  The best setting is then
evaluated on the whole RVM image for the figures behind each EC (the visual angles of A–C on
the display, the magnification and px per degree there, the silhouettes' visible fractions).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import yaml

from rvmsim.criteria import EcResult, load_criteria
from rvmsim.isp import load_params
from rvmsim.pipeline import evaluate_params
from rvmsim.render import cached_render
from rvmsim.scene import absolute_mesh_paths, load_scene, read_scene_document
from rvmsim.tune import RunOptions, TuneRequest, tune

ROOT = Path(__file__).resolve().parent.parent
CRITERIA = "fmvss111-full"


def scaled_scene_file(scene_file: Path, scale: float, folder: Path) -> Path:
    """A copy of the scene whose sensor is ``scale`` of the real one (same lens, same view),
    with absolute mesh paths, written into ``folder``."""
    scene, doc = read_scene_document(scene_file)
    absolute_mesh_paths(doc, scene_file.parent)
    cam = scene.fisheye_camera().scaled(scale)
    doc["camera"]["image_size"] = [cam.width, cam.height]
    doc["camera"]["intrinsics"] = {"fx": cam.fx, "fy": cam.fy, "cx": cam.cx, "cy": cam.cy,
                                   "skew": cam.skew}
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / f"{scene_file.stem}_x{scale:g}.yaml"
    out.write_text(yaml.safe_dump(doc, sort_keys=False))
    return out


def why(ec: EcResult) -> str:
    """The failing ECs, each with its value and the figures behind it."""
    details = ec.measurements.details
    parts = []
    for item in ec.items:
        if not item.enabled or item.passed:
            continue
        value = "not measured" if item.value is None else f"{item.value:.3g}{item.unit}"
        text = f"{item.id} {item.name} = {value} (range {_range(item.low, item.high)})"
        extra = _figures(item.id, details.get(item.id))
        parts.append(text + (f": {extra}" if extra else ""))
    return "; ".join(parts)


def _range(low: float | None, high: float | None) -> str:
    return f"[{'–' if low is None else f'{low:g}'}, {'–' if high is None else f'{high:g}'}]"


def _figures(ec_id: str, detail: Any) -> str:
    if not detail:
        return ""
    if ec_id == "1-5":
        return ", ".join(f"{c} {f:.0f} %" for c, f in detail[0].items() if f < 100.0)
    if ec_id == "1-6":
        return ", ".join(f"{c} {w['arcmin']:.2f}′ ({w['mm']:.2f} mm)" for c, w in detail.items())
    if ec_id == "6-1":
        return ", ".join(f"{c} ×{w['magnification']:.2f} {w['px_per_deg']:.2f} px/°"
                         for c, w in detail.items())
    return ""


def _summary(ec: EcResult) -> str:
    """The new ECs' key figures for every vehicle (worst object)."""
    d = ec.measurements.details
    size, res = d.get("1-6") or {}, d.get("6-1") or {}
    if not size or not res:
        return "—"
    arcmin = min(w["arcmin"] for w in size.values())
    mag = max(w["magnification"] for w in res.values())
    ppd = min(w["px_per_deg"] for w in res.values())
    return f"min {arcmin:.1f}′, ×{mag:.2f} max, {ppd:.2f} px/° min"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vehicles", default="abcdef", help="letters of scenes/vehicle_*.yaml")
    ap.add_argument("--scale", type=float, default=1.0, help="fraction of the sensor to tune")
    ap.add_argument("--budget", type=int, default=None, help="evaluations (default: tune's)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=ROOT / "runs" / "criteria_table")
    args = ap.parse_args()
    rows = []
    for letter in args.vehicles:
        scene_file = ROOT / "scenes" / f"vehicle_{letter}.yaml"
        if args.scale != 1.0:
            scene_file = scaled_scene_file(scene_file, args.scale, args.out / "scenes")
        run_dir = args.out / f"vehicle_{letter}"
        result = tune(TuneRequest((scene_file,), criteria_file=CRITERIA, budget=args.budget),
                      run_dir, options=RunOptions(args.workers), force=True)
        scene = load_scene(scene_file)
        params, output = load_params(run_dir / "top" / "rank_1.yaml")
        images, _ = cached_render(scene)
        ec = evaluate_params(images, params, output, load_criteria(CRITERIA), annotate=False).ec
        evals = result.outcome.evaluated + result.outcome.replayed
        verdict = "pass" if ec.passed else "FAIL: " + why(ec)
        rows.append((scene.name, f"{ec.score:.3f}", str(evals), _summary(ec), verdict))
    print(f"criteria {CRITERIA}, default strategy, seed 0"
          + ("" if args.scale == 1.0 else f", sensor scale {args.scale:g}")
          + ("" if args.budget is None else f", budget {args.budget}"))
    print()
    print("| vehicle | EC score | evaluations | 1-6 / 6-1 figures (A–C) | result |")
    print("|---|---|---|---|---|")
    for row in rows:
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
