"""``rvmsim render``, ``process`` and ``evaluate``: one scene's fisheye frame, its RVM image,
and the RVM image's ECs."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from .errors import Command
from .params import (ONLY_SUPPORTED, FiniteFloat, Integer, OutputFolder, check_scale,
                     default_folder, load_isp)

if TYPE_CHECKING:
    from ..isp import IspParams

__all__ = ["render", "process", "evaluate"]


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--scale", type=FiniteFloat(0.05, 4.0), default=1.0, show_default=True,
              help="Resample the sensor by this factor (0.25 for a quick preview).")
@click.option("--face-size", type=Integer(16, 4096), default=None,
              help="Cube face size in px (default: automatic, as dense as the fisheye image).")
@click.option("--site", default=None, metavar="NAME|FILE",
              help="Render the car at this test site (fmvss111, unr158, jp, or a site file; "
                   "docs/markets.md) [default: its FMVSS 111 site].")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def render(scene: Path, out: Path, scale: float, face_size: int | None, site: str | None,
           progress: bool) -> None:
    """Render the fisheye (P camera) colour and label images of SCENE.

    Writes fisheye_color.png, fisheye_labels.png (one uint8 label ID per pixel),
    fisheye_labels_preview.png (labels in colour) and render.json into the output folder.
    """
    from ..pipeline import write_fisheye
    from ..render import render_fisheye
    from ..scene import is_site_file, load_scene, load_site, site_scene

    sc = load_scene(scene)
    if site is not None:
        sc = site_scene(sc, load_site(site) if is_site_file(site) else site)
    cam = sc.fisheye_camera()
    if scale != 1.0:
        cam = cam.scaled(scale)
    images = render_fisheye(sc, camera=cam, face_size=face_size, progress=progress)
    write_fisheye(images, out, scene_file=scene, vehicle=sc.name)
    total = sum(images.timings.values())
    click.echo(
        f"rendered {sc.name}: {cam.width}x{cam.height} px, {len(images.faces)} cube faces of "
        f"{images.face_size} px in {total:.2f} s -> {out}"
    )


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file (YAML/JSON); default: the paper's Table 2 defaults.")
@click.option("--out", "-o", type=OutputFolder(), required=True, help="Output folder.")
@click.option("--scale", type=FiniteFloat(0.05, 4.0), default=1.0, show_default=True,
              help="Render the fisheye at this fraction of the sensor (RAD and shifts follow).")
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def process(scene: Path, params_file: Path | None, out: Path, scale: float,
            progress: bool) -> None:
    """Render SCENE and run the ISP: fisheye image -> RVM image.

    Writes rvm_color.png, rvm_labels.png (uint8 IDs), rvm_labels_preview.png,
    fisheye_roi.png (the fisheye image with the region the RVM image uses outlined in green)
    and isp.json (the parameters used).
    """
    from ..pipeline import render_rvm, write_processed
    from ..scene import load_scene

    params, output = load_isp(params_file)
    sc = load_scene(scene)
    check_scale(sc, params, scale)
    frame = render_rvm(sc, params, output, scale=scale, progress=progress)
    write_processed(frame, out, params)
    click.echo(f"processed {sc.name}: RVM image {output.width}x{output.height} px -> {out}")


@click.command(cls=Command, error_path=("out",))
@click.argument("scene", type=click.Path(path_type=Path))
@click.option("--params", "params_file", type=click.Path(path_type=Path), default=None,
              help="ISP params file (YAML/JSON); default: the paper's Table 2 defaults.")
@click.option("--criteria", "criteria_file", type=click.Path(path_type=Path), default=None,
              help="Criteria file (YAML); default: the paper's thresholds.")
@click.option("--markets", default=None, metavar="M1,M2,…",
              help="Judge the setting in every market (fmvss111-full, unr158, jp, or "
                   "SITE:CRITERIA): one table per market, exit 1 unless all pass.")
@click.option("--out", "-o", type=OutputFolder(), default=None,
              callback=default_folder("scene", lambda s: Path("out") / s.stem / "evaluate"),
              help="Output folder (default: out/<scene name>/evaluate).")
@click.option("--scale", type=FiniteFloat(0.05, 4.0), default=1.0, show_default=True,
              help="Render the fisheye at this fraction of the sensor (RAD and shifts follow).")
@ONLY_SUPPORTED
@click.option("--progress/--no-progress", default=True, help="Show a progress bar.")
def evaluate(scene: Path, params_file: Path | None, criteria_file: Path | None,
             markets: str | None, out: Path, scale: float, only_supported: bool,
             progress: bool) -> None:
    """Evaluate the RVM image of SCENE under ISP parameters: the eleven ECs and the EC score,
    judged at the RVM image of record (the scene's or criteria's display.rvm_image_px,
    default 1280x720) whatever output size the params file names.

    Prints the EC table and writes ec.json, ec_annotated.png (the measurements drawn on the RVM
    image), rvm_color.png and rvm_labels.png; with --markets one such folder per market and
    markets.json (docs/markets.md).  Exit status 0 when every EC passes (every market, with
    --markets), 1 when one fails, 2 on an error.
    """
    from ..criteria import check_supported, load_criteria
    from ..isp import params_judged_at
    from ..pipeline import record_output, render_rvm, write_evaluation
    from ..scene import load_scene

    params, output = load_isp(params_file)
    if markets is not None:
        if criteria_file is not None:
            raise click.UsageError("--criteria: give no criteria with --markets (each market "
                                   "has its own; a market may be SITE:CRITERIA)")
        _evaluate_markets(scene, params, output.mirror, markets, out, scale, progress)
        return
    sc = load_scene(scene)
    criteria = check_supported(sc, load_criteria(criteria_file), scene,
                               only_supported=only_supported)
    check_scale(sc, params, scale)
    # Judged at the RVM image of record, whatever size the params file was searched at.
    record = record_output(criteria, sc, output.mirror)
    frame = render_rvm(sc, params, record, criteria=criteria, scale=scale, annotate=True,
                       progress=progress)
    write_evaluation(frame, out, params, scene_file=scene, vehicle=sc.name,
                     criteria_file=criteria_file)
    click.echo(f"{sc.name} — criteria: {criteria.name} — judged at the RVM image of record, "
               f"{record.width}x{record.height} px")
    was = params_judged_at(params_file) if params_file is not None else None
    if was is not None and was != (record.width, record.height):
        click.echo(f"rvmsim: note: {params_file}: output.judged_at is {was[0]}x{was[1]}; "
                   f"judged here at {scene}'s RVM image of record, "
                   f"{record.width}x{record.height} px", err=True)
    click.echo(frame.ec.table())
    click.echo(f"wrote {out / 'ec.json'} and {out / 'ec_annotated.png'}")
    if not frame.ec.passed:  # a judging command: 1 when something it judged fails
        failing = [e.id for e in frame.ec.items if e.enabled and not e.passed]
        click.echo(f"not every EC passes: {', '.join(failing)}", err=True)
        sys.exit(1)


def _evaluate_markets(scene: Path, params: IspParams, mirror: bool, markets: str, out: Path,
                      scale: float, progress: bool) -> None:
    """``evaluate --markets``: each market's table and folder, the per-market rows, exit 1
    unless every market passes."""

    from ..markets import binding_row, evaluate_markets, parse_markets
    from ..pipeline import write_evaluation
    from ..scene import load_scene

    chosen = parse_markets(markets)
    sc = load_scene(scene)
    check_scale(sc, params, scale)
    verdicts = evaluate_markets(sc, params, chosen, mirror=mirror, scale=scale,
                                progress=progress)
    rows = []
    for v in verdicts:
        folder = out / v.member.market.name.replace("/", "_").replace(":", "_")
        write_evaluation(v.frame, folder, params, scene_file=scene, vehicle=sc.name,
                         criteria_file=v.member.market.criteria)
        click.echo(f"{v.member.name} ({v.member.market.title or v.member.market.spec}) — "
                   f"judged at {v.frame.output.width}x{v.frame.output.height} px")
        click.echo(v.frame.ec.table() + "\n")
        rows.append({"market": v.member.market.name, "site": v.member.scene.test_site.site,
                     "ec_score": v.frame.ec.score, "passed": v.passed, "failing": v.failing,
                     "binding": binding_row(v.frame.ec.items), "folder": folder.name})
    click.echo(f"{'market':<24} {'EC score':>8}  {'result':<6}  binding criterion")
    click.echo("\n".join(v.row() for v in verdicts))
    passed = all(v.passed for v in verdicts)
    (out / "markets.json").write_text(json.dumps(
        {"scene": str(scene), "vehicle": sc.name, "passed": passed, "markets": rows}, indent=2))
    click.echo(f"wrote {out / 'markets.json'} and one folder per market")
    if not passed:
        lost = [f"{v.member.name} ({', '.join(v.failing)})" for v in verdicts if not v.passed]
        click.echo(f"not every market passes: {'; '.join(lost)}", err=True)
        sys.exit(1)
