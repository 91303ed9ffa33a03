"""Scenes of the robustness tests: vehicle A at a fraction of its sensor, with a variation."""

from __future__ import annotations

from pathlib import Path

import yaml

from rvmsim.scene import Scene, scene_from_dict

ROOT = Path(__file__).resolve().parents[2]


def small_scene(scale: float = 0.25, *, variation: dict | None = None,
                render: dict | None = None, site: dict | None = None) -> Scene:
    """Vehicle A with its sensor (and focal lengths) at ``scale``, its ``variation``
    section replaced by ``variation`` (None: removed), ``render`` settings and
    ``test_site`` keys."""
    doc = yaml.safe_load((ROOT / "scenes" / "vehicle_a.yaml").read_text())
    w, h = doc["camera"]["image_size"]
    doc["camera"]["image_size"] = [round(w * scale), round(h * scale)]
    for k in ("fx", "fy"):
        doc["camera"]["intrinsics"][k] = float(doc["camera"]["intrinsics"][k]) * scale
    doc.pop("variation", None)
    if variation is not None:
        doc["variation"] = variation
    if render is not None:
        doc["render"] = render
    if site is not None:
        doc["test_site"] = {**doc.get("test_site", {}), **site}
    return scene_from_dict(doc, base_dir=ROOT / "scenes", source="vehicle_a_small.yaml")


#: ±1° on every angle, no position tolerance, no load states: one viewpoint.
ANGLES_ONLY = {"mount": {a: {"uniform": {"half_width": 1.0}}
                         for a in ("yaw_deg", "pitch_deg", "roll_deg")}}
