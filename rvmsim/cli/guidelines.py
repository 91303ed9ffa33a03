"""``rvmsim guidelines``: the parking guidelines of a scene's car through an ISP setting."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import click

from .errors import Command
from .params import FiniteFloat, OutputFolder, load_isp

__all__ = ["guidelines"]


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file (YAML/JSON); default: the paper's Table 2 defaults.")
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--steering", default=None, metavar="START:STOP:STEP|A,B,…",
              help="Steering-wheel angles, degrees (positive toward +X), e.g. -540:540:10 "
                   "[default: the car's whole range in 10° steps].")
@click.option("--check/--no-check", default=False, show_default=True,
              help="Paint the lines on the site, render, and measure the overlay against "
                   "them (G-1 static lines, G-2 trajectories at 0, ±50 %, ±100 %).")
@click.option("--limit-px", type=FiniteFloat(0.01, 100.0), default=1.0, show_default=True,
              help="G-1 / G-2: how far (px of the image of record) a line may lie from its "
                   "painted line.")
@click.option("--picture/--no-picture", default=True, show_default=True,
              help="Draw over the RVM picture (renders the scene, or reads the render cache).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def guidelines(scene: Path, params_file: Path | None, out: Path, steering: str | None,
               check: bool, limit_px: float, picture: bool, progress: bool) -> None:
    """Parking guidelines of SCENE's car through the ISP setting: distance marks, width
    lines and trajectory lines per steering angle, in display pixels of the RVM image of
    record (docs/guidelines.md).

    Writes OUT/guidelines.json (polylines per line and angle, with their ground points),
    guidelines.bin (the ECU table), guidelines.png and guidelines.svg.  With --check the
    exit status is 1 when a line lies more than --limit-px from its painted line.
    """
    from ..guidelines import (compute_guidelines, guideline_view, running_gear,
                              steering_angles)
    from ..guidelines.check import check_guidelines
    from ..guidelines.coverage import covered_by, required_coverage
    from ..guidelines.files import check_document, write_guidelines
    from ..isp import apply_map, build_map
    from ..render import cached_render
    from ..scene import load_scene

    params, output = load_isp(params_file)
    sc = load_scene(scene)
    gear = running_gear(sc)
    try:
        angles = steering_angles(gear, steering)
    except ValueError as err:
        raise click.BadParameter(str(err), param_hint="--steering") from None
    view = guideline_view(sc, params, output)
    gset = compute_guidelines(sc, view, angles)
    rvm = None
    extra: dict[str, Any] = {}
    covers: dict[str, Any] = {}
    if picture:
        images, _ = cached_render(sc, progress=progress)
        isp_map = build_map(params, (images.camera.width, images.camera.height), view.output)
        rvm = apply_map(images.color, isp_map)  # one map: the picture and the coverage
        covers = extra["covers"] = required_coverage(sc, gset, images.labels,
                                                     isp_map=isp_map, progress=progress)
    failed = False
    checked: dict[str, Any] = {}
    if check:
        checked = extra["check"] = check_document(
            check_guidelines(sc, params, output, progress=progress), limit_px)
        failed = not (checked["G-1"]["pass"] and checked["G-2"]["pass"])
    write_guidelines(out, gset, rvm, scene_file=str(scene),
                     params_file=str(params_file or ""), extra=extra)
    shown = sum(1 for line in gset.lines() if line.shown)
    click.echo(f"guidelines of {sc.name}: {len(gset.steering_deg)} steering angles, "
               f"{shown} of {len(gset.lines())} lines shown -> {out}")
    for site, objs in covers.items():
        for name, v in objs.items():
            click.echo(f"  covers {site} {name}'s required area (up to "
                       f"{v['fraction'] * 100:.1f} %): {covered_by(v)}")
    if check:
        click.echo(f"  G-1 static lines {checked['G-1']['value_px']:.2f} px, G-2 trajectories "
                   f"{checked['G-2']['value_px']:.2f} px (limit {limit_px:g} px): "
                   f"{'fail' if failed else 'pass'}")
    if failed:
        sys.exit(1)
