"""Any sample as a scene file (``rvmsim robustness --export-sample N``): the car robustness
judged, to be rendered in full and evaluated (``rvmsim evaluate``), viewed, or shared.

The sample's scene is the scene's document with

* ``camera.mount`` at the sample's rendered position (``render_position_mm`` added to the
  mount position, m) and its angles (the offsets added to the mount angles, degrees);
* ``load_state`` the sample's load state, pitching about the scene's *nominal* camera centre
  (``pivot_m``), as robustness moves the body (:mod:`rvmsim.scene.load_state`);
* mesh paths made absolute (the file loads from any folder), no ``variation`` (one car).

So the exported scene's camera and body are the sample's, to floating-point rounding (the
tests check it to the bit); ``rvmsim evaluate`` renders it directly where robustness re-folded
a cube rendered at the sample's viewpoint, so the EC values agree to within that re-fold's
label-border sampling (docs/robustness.md gives the measured differences).  A second file,
``sample_N.json``, holds what robustness measured on the sample (every EC's value and
verdict) and the command that reproduces it.  After end-of-line compensation the car is
judged with its own values: they are written as ``sample_N.params.yaml`` (the platform
setting with the per-car values, a params file of the RVM image of record), the command
evaluates that file, and the JSON holds the station's verdict and the verdict before
compensation beside it.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from ..errors import RvmsimError
from ..storage import write_problem, write_text
from ..isp import params_to_dict
from ..scene import Scene, absolute_mesh_paths
from .robustness import RobustnessResult
from .samples import MountSample
from .variation import NOMINAL_LOAD

__all__ = ["sample_scene_document", "SampleExport", "write_sample_scenes"]


def sample_scene_document(document: Mapping[str, Any], scene: Scene,
                          sample: MountSample) -> dict[str, Any]:
    """The scene document of ``sample`` (see the module docstring).

    Parameters
    ----------
    document : dict
        The scene file's parsed YAML (:func:`rvmsim.scene.read_scene_document`).
    scene : Scene
        The scene it validates to (its mount and folder).
    sample : MountSample
        From the robustness run.

    Returns
    -------
    dict
        A new document; ``document`` is not changed.
    """
    doc = copy.deepcopy(dict(document))
    absolute_mesh_paths(doc, scene.base_dir)
    doc.pop("variation", None)
    m = scene.camera.mount
    dy, dp, dr = sample.angles_deg
    camera = dict(doc["camera"])
    camera["mount"] = {
        "position": [p + d / 1000.0 for p, d in zip(m.position, sample.render_position_mm)],
        "yaw_deg": m.yaw_deg + dy, "pitch_deg": m.pitch_deg + dp, "roll_deg": m.roll_deg + dr}
    doc["camera"] = camera
    if sample.load != NOMINAL_LOAD:
        doc["load_state"] = {"name": sample.load.name, "height_mm": sample.load.height_mm,
                             "pitch_deg": sample.load.pitch_deg, "pivot_m": list(m.position)}
    offsets = ", ".join(f"{n} {v:+.3f}" for n, v in zip(
        ("x", "y", "z", "yaw", "pitch", "roll"), (*sample.render_position_mm, dy, dp, dr)))
    note = (f"robustness sample {sample.index} (tolerance x{sample.scale:g}): {offsets} "
            f"(mm at the rendered position, degrees), load {sample.load.name}")
    doc["description"] = f"{doc.get('description') or ''}\n{note}".strip()
    return doc


@dataclass(frozen=True)
class SampleExport:
    """How the robustness run was made, for the exported samples' notes: the params and
    criteria files (None: the defaults) and the render scale."""

    params_file: Path
    criteria_file: Path | None = None
    render_scale: float = 1.0


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def write_sample_scenes(result: RobustnessResult, document: Mapping[str, Any], scene: Scene,
                        numbers: Sequence[int], out_dir: str | Path,
                        how: SampleExport) -> list[Path]:
    """Write ``sample_N.yaml`` (the scene, :func:`sample_scene_document`) and
    ``sample_N.json`` (what robustness measured on it) into ``out_dir`` for each N of
    ``numbers``.

    Raises
    ------
    RvmsimError
        A sample number outside the run's samples, or a file that cannot be written (one
        line naming it).
    """
    out = Path(out_dir)
    ev = result.evaluation
    written: list[Path] = []
    for n in numbers:
        if not 0 <= n < len(result.samples):
            raise RvmsimError(f"--export-sample: no sample {n} (the run has "
                              f"{len(result.samples)}: 0 to {len(result.samples) - 1})")
        sample = result.samples[n]
        yaml_path, json_path = out / f"sample_{n}.yaml", out / f"sample_{n}.json"
        doc = sample_scene_document(document, scene, sample)
        comp = result.compensated
        params_path = out / f"sample_{n}.params.yaml"
        params_arg = str(how.params_file.resolve()) if comp is None else params_path.name
        command = (f"rvmsim evaluate {yaml_path.name} --params {params_arg}"
                   + (f" --criteria {how.criteria_file.resolve()}" if how.criteria_file else "")
                   + (f" --scale {how.render_scale:g}" if how.render_scale != 1.0 else ""))
        record: dict[str, Any] = {
            "sample": sample.as_dict(), "scene": str(yaml_path.name),
            "from_scene": scene.source, "seed": result.seed, "criteria": result.criteria_name,
            "render_scale": how.render_scale, "reproduce": command,
            "ec_score": float(ev.score[n]), "passed": bool(ev.all_passed[n]),
            "ecs": {e: {"value": _finite(float(ev.values[n, j])),
                        "passed": bool(ev.passed[n, j])} for j, e in enumerate(ev.ids)}}
        files = [(yaml_path, f"# {scene.name}: sample {n} of `rvmsim robustness "
                             f"{scene.source}` (seed {result.seed}); what robustness measured: "
                             f"{json_path.name}\n# reproduce: {command}\n"
                  + yaml.safe_dump(doc, sort_keys=False, allow_unicode=True))]
        if comp is not None and result.before is not None:
            sol = comp.solutions[n]
            record.update({
                "params": params_path.name, "platform_params": str(how.params_file.resolve()),
                "station": {"status": sol.status, "accepted": bool(comp.accepted[n]),
                            "reasons": list(sol.reasons), "law": sol.law},
                "passed_with_station": bool(result.passed[n]),
                "passed_before_compensation": bool(result.before.all_passed[n])})
            judged = result.judged_at or result.output
            files.append((params_path, (
                f"# {scene.name}: sample {n}'s own ISP setting after end-of-line compensation "
                f"({sol.law}: {', '.join(f'{k} {v:+.4f}' for k, v in sol.correction.offsets.items())} "
                f"from the platform setting {how.params_file.resolve()}); station: "
                f"{sol.status}\n# reproduce: {command}\n") + yaml.safe_dump(
                params_to_dict(sol.params, result.output, judged_at=judged), sort_keys=False)))
        files.append((json_path, json.dumps(record, indent=2) + "\n"))
        try:
            out.mkdir(parents=True, exist_ok=True)
            for path, text in files:
                write_text(path, text)
        except OSError as err:
            raise RvmsimError(f"{out}: {write_problem(err, f'cannot write sample {n}')}") \
                from None
        written += [path for path, _ in files]
    return written
