"""Benchmark: ``rvmsim robustness`` of vehicle A (not a test).

    python tools/bench_robustness.py [--params P.yaml] [--samples 200] [--snap-only]

Times :func:`rvmsim.robust.robustness` (the CLI's work: 200 samples at ±1° / ±5 mm and the
scene's load states, the yield curve over 0.5×–2× tolerances, the nominal and worst frames)
cold (an empty render cache) and with the renders cached, and, as the same-run baseline,
what full renders of every sample would cost (a few sample cameras rendered, extrapolated).

It also measures the error of rendering continuous position tolerances at a few levels per
axis (``position_levels``): for every sample, the scene's landmarks (test objects, board,
guidelines, and the bumper's top edge, the nearest surface) projected with the camera at its
drawn position and at its rendered position; the difference is the landmark error of the
approximation (rotations and loads are exact).  A few samples are also rendered in full at
their drawn position and compared with their sample images (label agreement).

Without ``--params`` a short tuning run (cmaes-solved, 300 evaluations) gives the setting.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

import numpy as np  # noqa: E402

from rvmsim.isp import load_params  # noqa: E402
from rvmsim.render import posed_parts  # noqa: E402
from rvmsim.robust import (RobustnessSettings, body_pose, draw_samples, robustness, sample_camera,  # noqa: E402
                           sample_images, variation_from_scene)
from rvmsim.scene import BlockPart, Scene, load_scene, site_landmarks  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def _bumper_edge(scene: Scene) -> np.ndarray:
    """Points on the bumper's top rear edge (scene frame, m): the surface nearest the camera."""
    b = scene.vehicle.bumper
    if not isinstance(b, BlockPart):
        return np.zeros((0, 3))
    xs = np.linspace(-0.45, 0.45, 7) * b.width
    z = -b.setback - b.sweep * (2 * xs / b.width) ** 2 - (b.top - b.bottom) * math.tan(
        math.radians(b.lean_deg))
    return np.stack([xs, np.full_like(xs, -b.top), z], axis=1)


def snap_error(scene: Scene, n: int, levels: int, seed: int) -> dict[str, float]:
    """Landmark error (fisheye px) of rendering positions at ``levels`` per axis."""
    var = dataclasses.replace(variation_from_scene(scene), position_levels=levels)
    samples = draw_samples(var, n, seed)
    site = np.array([lm.point for lm in site_landmarks(scene)])
    body = _bumper_edge(scene)
    errs_site, errs_body = [], []
    for s in samples:
        drawn = sample_camera(scene, s, rendered=False)
        rendered = sample_camera(scene, s)
        pose = body_pose(scene, s.load)
        body_s = body if pose is None else body @ pose[:3, :3].T + pose[:3, 3]
        for pts, out in ((site, errs_site), (body_s, errs_body)):
            a, ok_a = drawn.project(pts)
            b, ok_b = rendered.project(pts)
            ok = ok_a & ok_b & (np.abs(a[:, 0]) < 1e4)
            out.extend(np.linalg.norm(a[ok] - b[ok], axis=1).tolist())
    es, eb = np.array(errs_site), np.array(errs_body)
    return {"levels": levels, "site_rms": float(np.sqrt(np.mean(es ** 2))),
            "site_max": float(es.max()), "bumper_rms": float(np.sqrt(np.mean(eb ** 2))),
            "bumper_max": float(eb.max())}


def _full_render(scene: Scene, sample) -> np.ndarray:
    """Labels of a full render of ``sample`` at its drawn position (body moved by its load)."""
    from rvmsim.render import cube_layout, fold, render_faces
    from rvmsim.scene import build_parts

    cam = sample_camera(scene, sample, rendered=False)
    r = scene.render
    layout = cube_layout(cam, face_size=r.face_size_px, oversample=r.oversample,
                         max_face_size=r.max_face_size_px)
    parts = posed_parts(build_parts(scene), body_pose(scene, sample.load))
    atlas = render_faces(parts, layout, cam, sky=r.sky_color)
    return fold(layout, atlas.color, atlas.labels)[1]


def _tuned_params(scene_file: Path, folder: Path) -> Path:
    run = folder / "tune"
    subprocess.run([sys.executable, "-m", "rvmsim", "tune", str(scene_file), "--budget", "300",
                    "--out", str(run), "--no-progress"], check=True, capture_output=True)
    out = folder / "params.yaml"
    subprocess.run([sys.executable, "-m", "rvmsim", "select", str(run), "--out", str(out)],
                   check=True, capture_output=True)
    return out


def main() -> None:  # long: one report, step by step
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "scenes" / "vehicle_a.yaml"))
    ap.add_argument("--params", default=None)
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--baseline-renders", type=int, default=3)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="Local processes rendering the viewpoints (as rvmsim robustness).")
    ap.add_argument("--serial-baseline", action="store_true",
                    help="Also time a cold run rendering in this process only (the renders "
                         "as needed, one after another).")
    ap.add_argument("--snap-only", action="store_true",
                    help="Only the landmark error of the position levels.")
    args = ap.parse_args()
    scene = load_scene(args.scene)
    print(f"machine: {cpu_model()}, {os.cpu_count()} cores")
    print(f"scene: {scene.name}; variation: {variation_from_scene(scene).as_dict()['mount']}")
    print("\nlandmark error of rendering positions at a few levels (fisheye px):")
    for levels in (1, 2, 3):
        e = snap_error(scene, args.samples, levels, args.seed)
        print(f"  {levels} level(s)/axis: test site rms {e['site_rms']:.2f} max "
              f"{e['site_max']:.2f}; bumper edge rms {e['bumper_rms']:.2f} max "
              f"{e['bumper_max']:.2f}")
    k = args.baseline_renders
    samples = draw_samples(variation_from_scene(scene), args.samples, args.seed)[:k]
    t = time.perf_counter()
    fulls = [_full_render(scene, s) for s in samples]
    t_full = (time.perf_counter() - t) / max(k, 1)
    with tempfile.TemporaryDirectory() as tmp:
        os.environ["RVMSIM_CACHE"] = str(Path(tmp) / "cache")
        imgs = sample_images(scene, samples, color=False)
        agree = [float(np.mean(a.labels == b)) for a, b in zip(imgs, fulls)]
        print(f"  sample images (2 levels) vs full renders at the drawn position: label "
              f"agreement {', '.join(f'{100 * a:.2f} %' for a in agree)}")
        if args.snap_only:
            return
        params_file = Path(args.params) if args.params else _tuned_params(Path(args.scene),
                                                                           Path(tmp))
        params, output = load_params(params_file)
        from rvmsim.batch import LocalExecutor

        times = []
        if args.serial_baseline:
            os.environ["RVMSIM_CACHE"] = str(Path(tmp) / "cache-serial")
            t = time.perf_counter()
            res = robustness(scene, params, RobustnessSettings(output, samples=args.samples,
                                                                seed=args.seed))
            t_serial = time.perf_counter() - t
            print(f"\nrobustness cold, rendering here one after another: {t_serial:.1f} s "
                  f"({res.timings})")
        os.environ["RVMSIM_CACHE"] = str(Path(tmp) / "cache-run")
        for label in (f"cold, renders on {args.workers} processes", "cached"):
            t = time.perf_counter()
            with LocalExecutor(args.workers) as ex:
                res = robustness(scene, params, RobustnessSettings(
                    output, samples=args.samples, seed=args.seed), runner=ex)
            times.append(time.perf_counter() - t)
            print(f"\nrobustness {label}: {times[-1]:.1f} s ({res.timings})")
        if args.serial_baseline:
            print(f"cold: {t_serial / times[0]:.2f}x faster with the renders on "
                  f"{args.workers} processes")
        print(res.summary())
        t1 = time.perf_counter()
        robustness(scene, params, RobustnessSettings(output, samples=args.samples,
                                                     seed=args.seed, scales=(1.0,)))
        t_one = time.perf_counter() - t1
    print(f"\ncached, without the yield curve: {t_one:.1f} s")
    print(f"baseline: one full render per sample: {t_full:.2f} s each (mean of {k}) -> "
          f"{args.samples * t_full:.0f} s for {args.samples} samples "
          f"(+ {3 * min(args.samples, 64) * t_full:.0f} s for the yield curve); ratio "
          f"{args.samples * t_full / times[1]:.0f}x the cached run, "
          f"{args.samples * t_full / times[0]:.1f}x the cold one")


if __name__ == "__main__":
    main()
