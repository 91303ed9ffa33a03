"""Figures of `rvmsim eol` (not a test): the station on synthetic cars at the full sensor.

    python tools/bench_eol.py [--cars 20] [--seed 0] [--keep DIR]

The station of the tests (``rvmsim/testing/stations.py``: bundled vehicle A, 1280 × 960, a
station mat of 0.3 m squares behind the car, vehicle A's tuned setting) and ``--cars`` cars
whose camera mount deviates uniformly within ±1° and ±5 mm on every axis (seeded).  Each
car's capture is the station rendered from its camera (through the render cache).  Then:

1. a warm-up station run on one car (the station's nominal frame into the render cache,
   OpenGL and the imports started), and the timed runs on every car (``run_station``, as
   the command runs it: captures read, outputs written), in this process and with
   ``--workers`` processes (default 2);
2. per car: the recovered deviation minus the truth, the seconds of its station step, its
   verdict;
3. what robustness predicts for the same cars: each car through robustness's station step
   with a perfect station (``rvmsim.robust.CarJudge``: the model's law on robustness's own
   image of the car, its viewpoint rendered at the car's exact position, the rotation a
   re-fold) and judged there; the station's verdict should agree car for car.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402

from _bench_common import cpu_model  # noqa: E402

from rvmsim._io import write_png  # noqa: E402
from rvmsim.compensation import DEFAULT_COMPENSATION, Deviation  # noqa: E402
from rvmsim.criteria import default_criteria  # noqa: E402
from rvmsim.percar import ImagePicture, SplitEvaluator, make_law  # noqa: E402
from rvmsim.pipeline import record_output  # noqa: E402
from rvmsim.eol import (StationSettings, run_station, station_load,  # noqa: E402
                        synthetic_capture)
from rvmsim.report import write_eol_page  # noqa: E402
from rvmsim.robust import (CarJudge, MountSample, nominal_sample, refolder,  # noqa: E402
                           sample_images, station_twin, variation_from_scene)
from rvmsim.testing import stations as S  # noqa: E402


def _deviations(n: int, seed: int) -> list[Deviation]:
    rng = np.random.default_rng(seed)
    return [Deviation(*rng.uniform(-5.0, 5.0, 3), *rng.uniform(-1.0, 1.0, 3)) for _ in range(n)]


def _predicted(devs: list[Deviation]) -> tuple[np.ndarray, list[list[str]]]:
    """Robustness's verdict per car (perfect station) and the ECs it fails."""
    scene = S.station_scene(1.0)
    params, _ = S.platform(1.0)
    crit = default_criteria()
    model = DEFAULT_COMPENSATION.with_station(0.0, 0.0, 0.0)
    load = station_load(scene, model)
    record = record_output(crit, scene)
    samples = [MountSample(k, d.as_offsets(), (d.x_mm, d.y_mm, d.z_mm), load)
               for k, d in enumerate(devs)]
    shared = refolder(scene, samples)
    nominal = sample_images(scene, [station_twin(nominal_sample(variation_from_scene(scene)),
                                                 load)], color=False, shared=shared)[0]
    law = make_law(scene, params, record, model, crit,
                   ImagePicture(SplitEvaluator(nominal, record, crit)), nominal.camera)
    _, after, comp = CarJudge(scene, law, 0, load, crit, record)(samples, params, shared)
    ok = after.all_passed & comp.accepted
    fails = [[i for i, p, e in zip(crit.ids, row, after.enabled) if e and not p]
             for row in after.passed]
    return ok, fails


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cars", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--keep", type=Path, default=None, help="write the captures and outputs here")
    args = ap.parse_args()
    print(f"Python {platform.python_version()} on {cpu_model()} ({os.cpu_count()} cores)")
    scene = S.station_scene(1.0)
    params, output = S.platform(1.0)
    devs = _deviations(args.cars, args.seed)
    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_eol_"))
    caps = work / "captures"
    t = time.perf_counter()
    files = [write_png(caps / f"car{k:02d}.png", synthetic_capture(scene, d).color)
             for k, d in enumerate(devs)]
    print(f"{len(devs)} captures rendered (or read from the render cache) in "
          f"{time.perf_counter() - t:.1f} s")
    settings = StationSettings(params, output)
    t = time.perf_counter()
    run_station(scene, files[:1], work / "warm", settings)
    print(f"warm-up run (1 car, station set up): {time.perf_counter() - t:.1f} s")
    t = time.perf_counter()
    result = run_station(scene, files, work / "out", settings, write_page=write_eol_page)
    wall = time.perf_counter() - t
    t = time.perf_counter()
    par = run_station(scene, files, work / "out_workers", settings, workers=args.workers,
                      write_page=write_eol_page)
    wall_par = time.perf_counter() - t
    same = all(a.deviation == b.deviation and a.verdict == b.verdict
               for a, b in zip(result.cars, par.cars))
    t = time.perf_counter()
    predicted, fails = _predicted(devs)
    t_pred = time.perf_counter() - t
    _report(result, devs, predicted, fails, wall)
    print(f"with {args.workers} worker processes: {wall_par:.1f} s = "
          f"{wall_par / len(files):.2f} s per car (each worker sets up its own station); "
          f"results {'identical' if same else 'DIFFERENT'}")
    print(f"(robustness's prediction: {t_pred:.1f} s; outputs in {work / 'out'})")


def _report(result, devs, predicted, fails, wall) -> None:
    errs = np.array([np.array(c.deviation.as_offsets()) - np.array(d.as_offsets())
                     if c.deviation is not None else np.full(6, np.nan)
                     for c, d in zip(result.cars, devs)])
    print(f"\n{'car':<6}{'Δx,y,z mm (truth)':>22}{'Δypr ° (truth)':>22}{'error mm':>22}"
          f"{'error °':>24}{'s':>6}  station     robustness")
    for k, (c, d, e) in enumerate(zip(result.cars, devs, errs)):
        pred = "PASS" if predicted[k] else "FAIL " + ",".join(fails[k])
        print(f"{c.name:<6}{d.x_mm:+7.2f}{d.y_mm:+7.2f}{d.z_mm:+7.2f} "
              f"{d.yaw_deg:+7.3f}{d.pitch_deg:+7.3f}{d.roll_deg:+7.3f} "
              f"{e[0]:+7.2f}{e[1]:+7.2f}{e[2]:+7.2f} {e[3]:+8.4f}{e[4]:+8.4f}{e[5]:+8.4f}"
              f"{c.seconds:6.2f}  {c.verdict} {c.reason:<10} {pred}")
    n = len(result.cars)
    agree = sum(c.passed == bool(p) for c, p in zip(result.cars, predicted))
    secs = np.array([c.seconds for c in result.cars])
    print(f"\nrecovery error: position max {np.nanmax(np.abs(errs[:, :3])):.2f} mm "
          f"(RMS {np.sqrt(np.nanmean(errs[:, :3] ** 2)):.2f}), angles max "
          f"{np.nanmax(np.abs(errs[:, 3:])):.4f}° (RMS {np.sqrt(np.nanmean(errs[:, 3:] ** 2)):.4f})")
    print(f"per car: station step median {np.median(secs):.2f} s (max {secs.max():.2f}); "
          f"whole run {wall:.1f} s = {wall / n:.2f} s per car (captures read, outputs "
          f"written), setup {result.timings['setup']:.1f} s")
    print(f"{result.n_pass} of {n} cars pass at the station; robustness predicts "
          f"{int(np.sum(predicted))}; verdicts agree on {agree} of {n}")


if __name__ == "__main__":
    main()
