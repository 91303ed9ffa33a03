"""The ``guidelines`` output folder: guidelines.json, guidelines.bin (the ECU table),
guidelines.png and guidelines.svg, written whole or not at all
(:func:`rvmsim.storage.staged_folder`)."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from ..isp import params_to_dict
from ..storage import staged_folder
from .check import STATIC_KINDS, TRAJECTORY_KINDS, GuidelineCheck
from .draw import draw_lines, guidelines_svg
from .overlay import GuidelineSet
from .project import DisplayLine
from .table import table_bytes

__all__ = ["GUIDELINE_FILES", "guidelines_document", "write_guidelines", "shown_angle"]

#: The files of a guidelines folder.
GUIDELINE_FILES = ("guidelines.json", "guidelines.bin", "guidelines.png", "guidelines.svg")


def _line_doc(line: DisplayLine) -> dict[str, Any]:
    return {"name": line.name, "kind": line.kind, "color": list(line.color),
            "pieces": [{"uv_px": np.round(p.uv_px, 4).tolist(),
                        "ground_m": np.round(p.ground_m, 5).tolist()} for p in line.pieces]}


def shown_angle(gset: GuidelineSet) -> float:
    """The steering angle pictures show: the one nearest straight ahead."""
    return min(gset.steering_deg, key=abs)


def _png(rgb: np.ndarray) -> bytes:
    ok, data = cv2.imencode(".png", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR),
                            [cv2.IMWRITE_PNG_COMPRESSION, 2])
    if not ok:
        raise ValueError("the picture could not be encoded as PNG")
    return data.tobytes()


def check_document(check: GuidelineCheck, limit_px: float) -> dict[str, Any]:
    """The check's figures per line (px), and G-1 / G-2 against ``limit_px``."""
    g1 = check.worst_px(STATIC_KINDS)
    g2 = check.worst_px(TRAJECTORY_KINDS)
    return {
        "limit_px": limit_px,
        "G-1": {"value_px": g1, "pass": bool(g1 <= limit_px)},
        "G-2": {"value_px": g2, "pass": bool(g2 <= limit_px)},
        "lines": [{"name": c.name, "kind": c.kind, "steering_deg": c.steering_deg,
                   "scans": c.scans, "counted": int(len(c.offsets_px)),
                   "offset_px": c.offset_px, "offset_cm": c.offset_cm, "median_px": c.median_px, "p95_px": c.p95_px,
                   "max_px": c.max_px} for c in check.lines]}


def guidelines_document(gset: GuidelineSet, table: bytes, *, scene_file: str = "",
                        params_file: str = "", extra: Mapping[str, Any] | None = None
                        ) -> dict[str, Any]:
    """guidelines.json's content: the lines per steering angle in display px with their
    ground points, the table's hash, and what they were made from."""
    g = gset.gear
    out = gset.view.output
    return {
        "version": 1,
        "scene": scene_file,
        "params_file": params_file,
        "params": params_to_dict(gset.view.params),
        "output": {"size": [out.width, out.height], "mirror": out.mirror},
        "vehicle": {"width_m": gset.width_m, "wheelbase_m": g.wheelbase_m,
                    "rear_overhang_m": g.rear_overhang_m, "track_m": g.track_m,
                    "max_road_wheel_deg": g.max_road_wheel_deg,
                    "steering_range_deg": g.steering_range_deg},
        "spec": gset.spec.model_dump(mode="json"),
        "static": [_line_doc(l) for l in gset.static],
        "trajectories": [{"steering_deg": a,
                          "road_wheel_deg": float(g.road_wheel_deg(a)),
                          "lines": [_line_doc(l) for l in group]}
                         for a, group in zip(gset.steering_deg, gset.trajectories)],
        "table": {"file": "guidelines.bin", "format": "RVMG 1",
                  "sha256": hashlib.sha256(table).hexdigest(), "bytes": len(table)},
        **(dict(extra) if extra else {}),
    }


def write_guidelines(out: str | Path, gset: GuidelineSet, rvm_rgb: np.ndarray | None, *,
                     scene_file: str = "", params_file: str = "",
                     extra: Mapping[str, Any] | None = None) -> list[Path]:
    """Write the guidelines folder ``out`` (:data:`GUIDELINE_FILES`; without ``rvm_rgb``
    the picture is the lines on black).  Returns the files, in ``out``."""
    table = table_bytes(gset)
    doc = guidelines_document(gset, table, scene_file=scene_file, params_file=params_file,
                              extra=extra)
    out = Path(out)
    w, h = gset.view.output.width, gset.view.output.height
    base = rvm_rgb if rvm_rgb is not None else np.zeros((h, w, 3), np.uint8)
    picture = draw_lines(base, gset.at(shown_angle(gset)), gset.spec.line_width_px)
    # the SVG's picture as JPEG (a tenth of the PNG's bytes and time; the lines are vectors)
    ok, jpeg = cv2.imencode(".jpg", cv2.cvtColor(base, cv2.COLOR_RGB2BGR),
                            [cv2.IMWRITE_JPEG_QUALITY, 92])
    svg = guidelines_svg(gset, jpeg.tobytes() if ok and rvm_rgb is not None else None,
                         shown_deg=shown_angle(gset))
    with staged_folder(out) as stage:
        (stage / "guidelines.bin").write_bytes(table)
        # compact: the C encoder (an indented dump of 109 angles takes seconds)
        (stage / "guidelines.json").write_text(json.dumps(doc, separators=(",", ":")) + "\n")
        # cv2's encoder at a low compression level: a tenth of imageio's default time
        (stage / "guidelines.png").write_bytes(_png(picture))
        (stage / "guidelines.svg").write_text(svg)
    return [out / name for name in GUIDELINE_FILES]
