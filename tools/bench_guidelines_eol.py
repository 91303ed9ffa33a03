"""Benchmark figure of issue #46 (not a test): after the EOL step at the default station σ,
how far each car's parking guidelines land from where they claim, per bundled vehicle.

    PYTHONPATH=$PWD python3 tools/bench_guidelines_eol.py [--vehicles a,b,c,d,e,f]
        [--samples 1000] [--seed 0] [--params params/paper_defaults.yaml]
        [--ec-solve [--render-scale 0.25]]

For every vehicle (``scenes/vehicle_<v>.yaml``, its own tolerances and load states):

1. ``--samples`` cars drawn from its variation (Sobol, ``--seed``); the default compensation
   model's station reads each in its load state with its error (σ 0.1° and 1 mm per axis,
   :func:`rvmsim.robust.station_readings`);
2. each car's per-car values: by default the law ``reference-points``
   (:class:`rvmsim.compensation.CompensationLaw`, geometry only, no render); with
   ``--ec-solve`` the default law through :func:`rvmsim.robust.robustness` with
   compensation (renders at ``--render-scale``; slower);
3. :func:`rvmsim.robust.fleet_guideline_errors`: each car's table drawn from its measured
   pose and per-car values, looked at through its true pose (at the station, and in the
   field in its own load state), and the platform table (design pose, platform setting).

Prints per vehicle the 1 m mark's ground error (cm) over the cars: the 99th percentile (the
figure of #46), with the median and worst, and the display error (px), and the machine.
The ground error does not depend on the ISP values (a display pixel is one camera ray through
either pose; :mod:`rvmsim.guidelines.error`), only which parts of a line are shown does, so
the reference-points law and the platform setting of ``--params`` (the same file for every
vehicle) give the figure of any setting that shows the marks.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

from _bench_common import cpu_model  # noqa: E402

from rvmsim.compensation import DEFAULT_COMPENSATION, CompensationLaw  # noqa: E402
from rvmsim.eol import station_load  # noqa: E402
from rvmsim.guidelines import guideline_output  # noqa: E402
from rvmsim.isp import load_params  # noqa: E402
from rvmsim.robust import (FleetGuidelines, RobustnessSettings, draw_samples,  # noqa: E402
                           fleet_guideline_errors, robustness, station_readings,
                           variation_from_scene)
from rvmsim.scene import load_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MARK = "mark_1m"


def _geometric(scene: Any, params: Any, output: Any, n: int, seed: int) -> FleetGuidelines:
    """The fleet with the reference-points law's per-car values (no render)."""
    var = variation_from_scene(scene)
    samples = draw_samples(var, n, seed)
    load = station_load(scene, DEFAULT_COMPENSATION, var)
    measured = station_readings(scene, samples, DEFAULT_COMPENSATION, seed, load)
    law = CompensationLaw(scene, params, guideline_output(scene, output), DEFAULT_COMPENSATION)
    per_car = [law.correct(m).params for m in measured]
    lines = fleet_guideline_errors(scene, samples, measured, per_car, params, output, load)
    if lines is None:
        raise SystemExit(f"{scene.source}: the vehicle has no running gear")
    return lines


def _ec_solve(scene: Any, params: Any, output: Any, n: int, seed: int,
              render_scale: float) -> FleetGuidelines:
    """The fleet through robustness with the default compensation (law ec-solve)."""
    r = robustness(scene, params, RobustnessSettings(
        output, samples=n, seed=seed, scales=(1.0,), render_scale=render_scale,
        compensation=DEFAULT_COMPENSATION), frames=False, progress=True)
    if r.guidelines is None:
        raise SystemExit(f"{scene.source}: the vehicle has no running gear")
    return r.guidelines


def _cell(d: dict[str, Any]) -> str:
    return " / ".join("—" if d[k] is None else f"{d[k]:.2f}" for k in ("p99", "median", "max"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vehicles", default="a,b,c,d,e,f")
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--params", type=Path, default=ROOT / "params" / "paper_defaults.yaml")
    ap.add_argument("--ec-solve", action="store_true",
                    help="per-car values from the default law through robustness (renders)")
    ap.add_argument("--render-scale", type=float, default=0.25)
    args = ap.parse_args(argv)
    params, output = load_params(args.params)
    m = DEFAULT_COMPENSATION
    law = "ec-solve through robustness" if args.ec_solve else "reference-points"
    print(f"# 1 m mark after EOL: {args.samples} cars per vehicle, seed {args.seed}, station "
          f"σ {m.angle_sigma_deg:g}° / {m.position_sigma_mm:g} mm (measured at "
          f"{m.measured_at or 'the first load state'}), per-car values: {law}, platform "
          f"{args.params.name}")
    print(f"Python {platform.python_version()}, {platform.system()} {platform.machine()}, "
          f"{cpu_model()} ({os.cpu_count()} cores)\n")
    print("| vehicle | ground cm at the station: p99 / median / worst | in the field: p99 / "
          "median / worst | display px in the field: p99 / median / worst | platform table "
          "in the field, cm: p99 / median / worst | cars | s |")
    print("|---|---|---|---|---|---|---|")
    for v in args.vehicles.split(","):
        t0 = time.perf_counter()
        scene = load_scene(ROOT / "scenes" / f"vehicle_{v}.yaml")
        lines = (_ec_solve(scene, params, output, args.samples, args.seed, args.render_scale)
                 if args.ec_solve else
                 _geometric(scene, params, output, args.samples, args.seed))
        st = lines.eol_station.distribution()[MARK]
        fi = lines.eol_field.distribution()[MARK]
        pl = lines.platform_field.distribution()[MARK]
        print(f"| {v} | {_cell(st['cm'])} | {_cell(fi['cm'])} | {_cell(fi['px'])} | "
              f"{_cell(pl['cm'])} | {fi['cars']} | {time.perf_counter() - t0:.1f} |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
