"""What ``rvmsim calibrate`` writes: ``calibration.json`` (K, D, RMS per view),
``coverage.png`` (where the corners fell), ``camera.yaml`` (the scene's camera block), and
the camera section of a scene file (``--write-scene``)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .._io import write_png
from ..errors import RvmsimError
from .board import BoardSpec
from .intrinsics import BoardView, Calibration

__all__ = ["camera_block", "coverage_image", "write_calibration_outputs", "write_scene_camera"]

#: The camera keys ``--write-scene`` replaces; everything else in the scene is kept.
CAMERA_KEYS = ("image_size", "intrinsics", "lens")


def camera_block(K: np.ndarray, D: np.ndarray, image_size: tuple[int, int],
                 fov_deg: float | None = None) -> dict[str, Any]:
    """The scene's ``camera`` keys for a cv2.fisheye calibration: ``image_size``,
    ``intrinsics.K`` and ``lens`` (``kannala_brandt``, ``k`` = D; ``fov_deg`` when given).
    The mount is not part of it (a calibration says nothing about where the camera sits)."""
    lens: dict[str, Any] = {"model": "kannala_brandt", "k": [float(x) for x in np.ravel(D)]}
    if fov_deg is not None:
        lens["fov_deg"] = float(fov_deg)
    return {"image_size": [int(image_size[0]), int(image_size[1])],
            "intrinsics": {"K": [[float(x) for x in row] for row in np.asarray(K)]},
            "lens": lens}


def coverage_image(calib: Calibration, views: list[BoardView]) -> np.ndarray:
    """(H, W, 3) uint8: every view's corners on a dark canvas of the image size, used views
    in green (each view's outline in grey), rejected views in red."""
    import cv2

    w, h = calib.image_size
    img = np.full((h, w, 3), 24, np.uint8)
    for fit, view in zip(calib.views, views):
        pts = view.corners.astype(np.float32)
        hull = cv2.convexHull(pts).astype(np.int32)
        cv2.polylines(img, [hull], True, (110, 110, 110), 1, cv2.LINE_AA)
        color = (60, 220, 60) if fit.used else (230, 40, 40)
        for x, y in np.rint(pts).astype(int):
            cv2.circle(img, (int(x), int(y)), 2, color, -1, cv2.LINE_AA)
    return img


def write_calibration_outputs(calib: Calibration, views: list[BoardView], board: BoardSpec,
                              out: str | Path, fov_deg: float | None = None) -> list[Path]:
    """Write ``calibration.json``, ``coverage.png`` and ``camera.yaml`` into ``out``;
    returns their paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    doc = {
        "K": calib.K.tolist(), "D": calib.D.tolist(), "image_size": list(calib.image_size),
        "rms_px": calib.rms_px,
        "board": {"inner_corners": list(board.inner), "square_size_m": board.square_size},
        "views": [{"name": v.name, "rms_px": v.rms_px, "max_px": v.max_px, "used": v.used,
                   "rvec": list(v.rvec), "tvec_m": list(v.tvec)} for v in calib.views],
    }
    paths = [out / "calibration.json", out / "coverage.png", out / "camera.yaml"]
    paths[0].write_text(json.dumps(doc, indent=2) + "\n")
    write_png(paths[1], coverage_image(calib, views))
    block = {"camera": camera_block(calib.K, calib.D, calib.image_size, fov_deg)}
    paths[2].write_text("# rvmsim calibrate: the scene's camera block (add camera.mount)\n"
                        + yaml.safe_dump(block, sort_keys=False, default_flow_style=None))
    return paths


def write_scene_camera(scene_file: str | Path, block: dict[str, Any]) -> Path:
    """Replace ``camera.image_size``, ``camera.intrinsics`` and ``camera.lens`` of a scene
    file with ``block`` (a :func:`camera_block`), keeping every other key (``fov_deg`` of
    the scene's lens is kept when ``block`` has none).  The result is loaded as a scene
    before it replaces the file (atomically); comments in the file are not kept.

    Raises
    ------
    RvmsimError or SceneError
        The scene cannot be read, or the result does not load.
    """
    import copy

    from ..scene import read_scene_document, scene_from_dict

    path = Path(scene_file)
    _, doc = read_scene_document(path)
    cam = doc["camera"]
    lens = dict(block["lens"])
    old_lens = cam.get("lens") if isinstance(cam.get("lens"), dict) else {}
    if "fov_deg" not in lens and "fov_deg" in old_lens:
        lens["fov_deg"] = old_lens["fov_deg"]
    for key in CAMERA_KEYS:
        cam[key] = lens if key == "lens" else block[key]
    scene_from_dict(copy.deepcopy(doc), base_dir=path.parent, source=str(path))
    tmp = path.with_name(f".{path.name}.calibrate.tmp")
    try:
        tmp.write_text(yaml.safe_dump(doc, sort_keys=False, default_flow_style=None))
        os.replace(tmp, path)
    except OSError as err:
        raise RvmsimError(f"{path}: cannot write the scene ({err.strerror or err})") from None
    finally:
        if tmp.exists():
            tmp.unlink()
    return path
