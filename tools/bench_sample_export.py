"""Benchmark: how closely a full render of an exported sample reproduces what robustness
measured on it (not a test).

    python tools/bench_sample_export.py --params P.yaml [--scene scenes/vehicle_a.yaml]
        [--samples 200] [--seed 0] [--exports 20] [--scale 1]

Runs :func:`rvmsim.robust.robustness` (the scene's variation, one tolerance factor), prints
every EC's sensitivity fit, then writes ``--exports`` loaded samples (spread over the run) as
scenes (:func:`rvmsim.robust.sample_scene_document`), renders each in full as ``rvmsim
evaluate`` does (:func:`rvmsim.pipeline.render_rvm`), and compares: the fisheye label images
(share of pixels equal, and how many of the others lie off a label border) and every EC's
value and verdict against robustness's.  The exported scene's camera and body are the
sample's, so what is left is the re-fold's label-border sampling (docs/robustness.md).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

import numpy as np  # noqa: E402

from rvmsim.criteria import default_criteria  # noqa: E402
from rvmsim.isp import load_params  # noqa: E402
from rvmsim.pipeline import evaluate_params  # noqa: E402
from rvmsim.render import render_fisheye  # noqa: E402
from rvmsim.robust import (RobustnessSettings, robustness, sample_images,  # noqa: E402
                           sample_scene_document)
from rvmsim.scene import read_scene_document, scene_from_dict  # noqa: E402


def _off_border(a: np.ndarray, b: np.ndarray) -> tuple[float, int]:
    """Share of equal labels, and the differing pixels with no other label among their 8
    neighbours in ``b`` (not a border's sampling)."""
    bad = a != b
    lab = b.astype(np.int32)
    border = np.zeros_like(bad)
    for dy, dx in ((0, 1), (1, 0), (0, -1), (-1, 0), (1, 1), (-1, -1), (1, -1), (-1, 1)):
        border |= np.roll(np.roll(lab, dy, 0), dx, 1) != lab
    return 1.0 - float(bad.mean()), int((bad & ~border).sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", type=Path, default=Path("scenes/vehicle_a.yaml"))
    ap.add_argument("--params", type=Path, required=True)
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--exports", type=int, default=20)
    ap.add_argument("--scale", type=float, default=1.0)
    args = ap.parse_args()
    scene, document = read_scene_document(args.scene)
    params, output = load_params(args.params)
    crit = default_criteria()
    t0 = time.perf_counter()
    res = robustness(scene, params, RobustnessSettings(output, crit, samples=args.samples,
                                                       seed=args.seed, scales=(1.0,),
                                                       render_scale=args.scale),
                     frames=False)
    print(f"{cpu_model()}; robustness {time.perf_counter() - t0:.1f} s")
    print(res.summary())
    for e in res.ecs:
        if e.sensitivity is not None:
            print("  ", e.sensitivity.describe())
    loaded = [i for i, s in enumerate(res.samples) if s.load.height_mm or s.load.pitch_deg]
    picks = [loaded[k] for k in np.linspace(0, len(loaded) - 1, min(args.exports, len(loaded)),
                                            dtype=int)]
    ev, ids = res.evaluation, res.evaluation.ids
    diffs, flips, agree = [], 0, []
    for n in picks:
        s = res.samples[n]
        ex = scene_from_dict(sample_scene_document(document, scene, s), source=f"sample_{n}")
        cam = ex.fisheye_camera()
        cam = cam.scaled(args.scale) if args.scale != 1.0 else cam
        full = render_fisheye(ex, camera=cam)
        frame = evaluate_params(full, params.for_input_scale(cam.width / ex.camera.image_size[0])
                                if args.scale != 1.0 else params, output, crit)
        ref = sample_images(scene, [s], scale=args.scale, color=False)[0]
        share, off = _off_border(full.labels, ref.labels)
        agree.append(share)
        v = np.array([np.nan if frame.ec[e].value is None else frame.ec[e].value for e in ids])
        d = v - ev.values[n]
        diffs.append(d)
        flip = [e for j, e in enumerate(ids) if frame.ec[e].passed != bool(ev.passed[n, j])]
        flips += bool(flip)
        print(f"sample {n:3d} ({s.load.name}): labels {100 * share:.2f} % equal, {off} off a "
              f"border; EC differences {np.round(d, 3).tolist()}; verdicts differ: {flip}")
    dd = np.abs(np.array(diffs))
    print(f"\n{len(picks)} loaded samples: labels {100 * min(agree):.2f}–{100 * max(agree):.2f} %"
          f" equal; {len(picks) - flips} of {len(picks)} with every verdict the same")
    print("| EC | unit | max abs difference | RMS | samples differing |")
    print("|---|---|---|---|---|")
    for j, e in enumerate(ids):
        col = dd[:, j][np.isfinite(dd[:, j])]
        if col.size:
            print(f"| {e} | {crit.ecs[j].unit} | {col.max():.3g} | "
                  f"{np.sqrt(np.mean(col ** 2)):.3g} | {int(np.sum(col > 1e-9))} |")


if __name__ == "__main__":
    main()
