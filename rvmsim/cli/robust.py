"""``rvmsim robustness``: the yield of one ISP setting over production variation."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .errors import Command
from .params import (DEFAULT_WORKERS, SEED, FiniteFloat, Integer, OutputFolder,
                     SchedulerAddress, check_scale, load_isp, scale_factors)

__all__ = ["robustness"]


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), required=True,
              help="ISP params file (YAML/JSON) to sign off.")
@click.option("--samples", type=Integer(1, 100000), default=200, show_default=True,
              help="Variation samples (Sobol, scrambled).")
@click.option("--seed", type=SEED, default=0, show_default=True,
              help="Scrambling seed: the same seed, the same samples.")
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--min-yield", type=FiniteFloat(0, 1), default=None,
              help="Exit 1 when the yield (0-1) is below this.")
@click.option("--variation", "variation_file", type=click.Path(path_type=Path), default=None,
              help="Variation file (default: the scene's variation section).")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--scale", type=FiniteFloat(0.05, 1.0), default=1.0, show_default=True,
              help="Render at this fraction of the sensor (RAD and shifts follow).")
@click.option("--scales", default="0.5,1,1.5,2", show_default=True, callback=scale_factors,
              help="Tolerance scale factors of the yield curve (comma-separated; each other "
                   "than 1 needs its own renders).")
@click.option("--scale-samples", type=Integer(1, 100000), default=None,
              help="Samples per tolerance scale factor of the yield curve (default: "
                   "min(--samples, 64)).")
@click.option("--workers", type=Integer(1, 64), default=DEFAULT_WORKERS,
              show_default=True, help="Local processes rendering the viewpoints not yet in "
                                      "the render cache.")
@click.option("--scheduler", type=SchedulerAddress(), default=None, metavar="tcp://HOST:PORT",
              help="Render those viewpoints on this Dask distributed cluster instead (the "
                   "scene's mesh files must be readable there at the same paths).")
@click.option("--compensation", default=None, metavar="FILE|default",
              help="Judge every sample after end-of-line compensation: a compensation file "
                   "(or a variation file with a compensation section), or 'default' "
                   "(docs/compensation.md).  The yield is then the yield after it; the "
                   "yield before is reported beside it.")
@click.option("--export-sample", "export_samples", type=Integer(0, 99999), multiple=True,
              metavar="N", help="Also write sample N's scene (its mount offsets and load "
                                "state; repeatable) as OUT/sample_N.yaml, with what was "
                                "measured on it in OUT/sample_N.json.")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def robustness(scene: Path, params_file: Path, samples: int, seed: int, out: Path,
               min_yield: float | None, variation_file: Path | None,
               criteria_file: Path | None, scale: float, scales: tuple[float, ...],
               scale_samples: int | None, workers: int, scheduler: str | None,
               compensation: str | None, export_samples: tuple[int, ...],
               progress: bool) -> None:
    """Yield of the ISP setting in --params over SCENE's production variation.

    Draws mount-tolerance and load-state samples (the scene's variation section, or
    --variation), evaluates every EC on each, and writes robustness.json and
    robustness.html.  With --compensation each car is first corrected at the end of the
    line (its measured deviation turned into per-car ISP values) and the yield is the yield
    after that.  With --export-sample N, also sample N as a scene file (``rvmsim evaluate``
    renders it in full: docs/robustness.md).  Exit status: 0 the yield is at least
    --min-yield (or none given), 1 below it, 2 an error.
    """
    from ..batch import make_executor
    from ..compensation import compensation_for
    from ..criteria import load_criteria
    from ..report import RobustnessInputs, write_robustness_outputs
    from ..robust import RobustnessSettings, variation_for
    from ..robust import SampleExport, write_sample_scenes
    from ..robust import robustness as run_robustness
    from ..scene import read_scene_document

    for n in export_samples:
        if n >= samples:
            raise click.BadParameter(f"no sample {n}: --samples {samples} draws samples 0 to "
                                     f"{samples - 1}", click.get_current_context(),
                                     param_hint="--export-sample")
    params, output = load_isp(params_file)
    criteria = load_criteria(criteria_file)
    sc, document = read_scene_document(scene)
    check_scale(sc, params, scale)
    settings = RobustnessSettings(output, criteria, variation_for(sc, variation_file), samples,
                                  seed, scales, scale_samples, scale, min_yield,
                                  compensation_for(compensation))
    with make_executor(scheduler, workers) as runner:
        result = run_robustness(sc, params, settings, runner=runner, progress=progress)
    written = write_robustness_outputs(result, out, RobustnessInputs(
        params_file, criteria_file, variation_file, compensation, scale))
    written += write_sample_scenes(result, document, sc, export_samples, out,
                                   SampleExport(params_file, criteria_file, scale))
    click.echo(result.summary())
    click.echo(f"wrote {', '.join(p.name for p in written)} in {out} "
               f"({result.timings['total']:.1f} s)")
    sys.exit(0 if result.meets_min_yield else 1)
