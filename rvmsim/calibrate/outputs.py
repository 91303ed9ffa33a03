"""What ``rvmsim calibrate`` writes: ``calibration.json`` (K, D, RMS per view),
``coverage.png`` (where the corners fell), the corners dropped as outliers, ``camera.yaml`` (the scene's camera block), and
the camera section of a scene file (``--write-scene``)."""

from __future__ import annotations

import copy
import json
import os
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from .._io import read_text, write_png
from ..errors import RvmsimError, SceneError
from ..scene import read_scene_document, scene_from_dict
from ..storage import staged_folder, write_text
from .board import BoardSpec
from .intrinsics import BoardView, Calibration

__all__ = ["camera_block", "coverage_image", "replace_camera_values", "write_calibration_outputs",
           "write_scene_camera"]

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
    in green (each view's outline in grey), rejected views in red, corners dropped as
    outliers ringed in orange."""

    w, h = calib.image_size
    img = np.full((h, w, 3), 24, np.uint8)
    for fit, view in zip(calib.views, views):
        pts = view.corners.astype(np.float32)
        hull = cv2.convexHull(pts).astype(np.int32)
        cv2.polylines(img, [hull], True, (110, 110, 110), 1, cv2.LINE_AA)
        color = (60, 220, 60) if fit.used else (230, 40, 40)
        for x, y in np.rint(pts).astype(int):
            cv2.circle(img, (int(x), int(y)), 2, color, -1, cv2.LINE_AA)
        for j in fit.dropped:  # outlier corners: an orange ring
            x, y = np.rint(pts[j]).astype(int)
            cv2.circle(img, (int(x), int(y)), 5, (255, 150, 0), 1, cv2.LINE_AA)
    return img


def write_calibration_outputs(calib: Calibration, views: list[BoardView], board: BoardSpec,
                              out: str | Path, fov_deg: float | None = None) -> list[Path]:
    """Write ``calibration.json``, ``coverage.png`` and ``camera.yaml`` into ``out``
    (:func:`~rvmsim.storage.staged_folder`: all of them or, on an error, none); returns
    their paths."""
    out = Path(out)
    doc = {
        "K": calib.K.tolist(), "D": calib.D.tolist(), "image_size": list(calib.image_size),
        "rms_px": calib.rms_px,
        "board": {"inner_corners": list(board.inner), "square_size_m": board.square_size,
                  **({} if board.charuco is None else {
                      "pattern": "charuco", "squares": list(board.charuco.squares),
                      "marker_size_m": board.charuco.marker_size,
                      "aruco_dictionary": board.charuco.dictionary})},
        "views": [{"name": v.name, "corners": int(len(view.corners)), "rms_px": v.rms_px,
                   "max_px": v.max_px, "used": v.used, "rvec": list(v.rvec),
                   "tvec_m": list(v.tvec),
                   "dropped_corners": [{"index": j, "px": [float(x) for x in view.corners[j]],
                                        "error_px": e}
                                       for j, e in zip(v.dropped, v.dropped_px)]}
                  for v, view in zip(calib.views, views)],
    }
    paths = [out / "calibration.json", out / "coverage.png", out / "camera.yaml"]
    block = {"camera": camera_block(calib.K, calib.D, calib.image_size, fov_deg)}
    with staged_folder(out) as stage:
        write_text(stage / paths[0].name, json.dumps(doc, indent=2) + "\n")
        write_png(stage / paths[1].name, coverage_image(calib, views))
        write_text(stage / paths[2].name,
                   "# rvmsim calibrate: the scene's camera block (add camera.mount)\n"
                   + yaml.safe_dump(block, sort_keys=False, default_flow_style=None))
    return paths


def write_scene_camera(scene_file: str | Path, block: dict[str, Any]) -> Path:
    """Replace ``camera.image_size``, ``camera.intrinsics`` and ``camera.lens`` of a scene
    file with ``block`` (a :func:`camera_block`), keeping every other key (``fov_deg`` of
    the scene's lens is kept when ``block`` has none).

    The three values are rewritten in the file's text (:func:`replace_camera_values`), so
    comments and layout elsewhere stay; only where that cannot be done (a flow-style
    ``camera: {…}``) is the document dumped again, without its comments.  The result is
    loaded as a scene before it replaces the file (atomically).

    Raises
    ------
    RvmsimError or SceneError
        The scene cannot be read, or the result does not load.
    """

    path = Path(scene_file)
    _, doc = read_scene_document(path)
    cam = doc["camera"]
    lens = dict(block["lens"])
    old_lens = cam.get("lens") if isinstance(cam.get("lens"), dict) else {}
    if "fov_deg" not in lens and "fov_deg" in old_lens:
        lens["fov_deg"] = old_lens["fov_deg"]
    values = {key: (lens if key == "lens" else block[key]) for key in CAMERA_KEYS}
    cam.update(values)
    scene_from_dict(copy.deepcopy(doc), base_dir=path.parent, source=str(path))
    text = replace_camera_values(read_text(path, SceneError), values, doc)
    if text is None:
        text = yaml.safe_dump(doc, sort_keys=False, default_flow_style=None)
    tmp = path.with_name(f".{path.name}.calibrate.tmp")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError as err:
        raise RvmsimError(f"{path}: cannot write the scene ({err.strerror or err})") from None
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def _dump_block(value: object, column: int) -> str:
    """``value`` as block YAML (leaf lists in flow style), every line indented by
    ``column``."""
    text = yaml.safe_dump(value, sort_keys=False, default_flow_style=None)
    return "".join(" " * column + ln for ln in text.splitlines(keepends=True))


def _dump_flow(value: object) -> str:
    """``value`` as one line of flow YAML."""
    return yaml.safe_dump(value, default_flow_style=True, sort_keys=False, width=10**6).strip()


def replace_camera_values(text: str, values: dict[str, Any],
                          expected: dict[str, Any]) -> str | None:
    """``text`` (a scene YAML document) with ``camera.<key>`` set to ``values[key]``,
    rewritten in place: each value in the style it had (a flow value on its line, a block
    value as its lines), a missing key added as the camera's first; every other line,
    comments included, unchanged.

    Returns None when that cannot be done (``camera`` missing or in flow style) or the
    result does not parse to ``expected`` (the whole document as it should be).

    Convention
    ----------
    Lines and columns as PyYAML's marks: 0-based.
    """
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return None
    if not isinstance(root, yaml.MappingNode):
        return None
    cam = next((v for k, v in root.value if k.value == "camera"), None)
    if not isinstance(cam, yaml.MappingNode) or cam.flow_style or not cam.value:
        return None
    lines = text.splitlines(keepends=True)
    # (first line, first column, end line, end column, new text); applied bottom-up.
    edits: list[tuple[int, int, int, int, str]] = []
    child_col = cam.value[0][0].start_mark.column
    for key in CAMERA_KEYS:
        pair = next(((k, v) for k, v in cam.value if k.value == key), None)
        if pair is None:
            at = cam.value[0][0].start_mark.line
            edits.append((at, 0, at, 0, _dump_block({key: values[key]}, child_col)))
            continue
        k, v = pair
        if isinstance(v, yaml.ScalarNode) or v.flow_style:
            edits.append((v.start_mark.line, v.start_mark.column, v.end_mark.line,
                          v.end_mark.column, _dump_flow(values[key])))
            continue
        first = k.start_mark.line + 1
        # A block value ends where the next token starts (the next key's line, or the end).
        el, ec = v.end_mark.line, v.end_mark.column
        end = el if el >= len(lines) or not lines[el][:ec].strip() else el + 1
        while end > first and lines[end - 1].strip() in ("",) or (
                end > first and lines[end - 1].lstrip().startswith("#")):
            end -= 1  # blank and comment lines after the value belong to what follows
        column = v.start_mark.column if isinstance(v, yaml.SequenceNode) else \
            v.value[0][0].start_mark.column if v.value else k.start_mark.column + 2
        body = yaml.safe_dump(values[key], sort_keys=False, default_flow_style=None)
        if body.count("\n") == 1:  # a flow list or a scalar: on the key's own line
            colon = lines[k.start_mark.line].index(":", k.end_mark.column) + 1
            edits.append((first, 0, end, 0, ""))
            edits.append((k.start_mark.line, colon, k.start_mark.line, colon,
                          " " + body.strip()))
            continue
        edits.append((first, 0, end, 0, "".join(" " * column + ln
                                               for ln in body.splitlines(keepends=True))))
    for l0, c0, l1, c1, new in sorted(edits, reverse=True):
        head = "".join(lines[:l0]) + (lines[l0][:c0] if l0 < len(lines) else "")
        tail = (lines[l1][c1:] if l1 < len(lines) else "") + "".join(lines[l1 + 1:])
        text = head + new + tail
        lines = text.splitlines(keepends=True)
    try:
        ok = yaml.safe_load(text) == expected
    except yaml.YAMLError:
        ok = False
    return text if ok else None
