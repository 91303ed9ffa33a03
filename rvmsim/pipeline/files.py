"""What the commands write: a frame's images, ``rvmsim process``'s and ``evaluate``'s
outputs, ``rvmsim render``'s fisheye images."""

from __future__ import annotations

import json
from pathlib import Path

from .. import labels as L
from .._io import write_png
from ..isp import IspParams, draw_roi, params_to_dict
from ..render import FisheyeImages
from .frame import RvmFrame

__all__ = ["write_frame", "write_processed", "write_evaluation", "write_fisheye"]


def write_frame(frame: RvmFrame, folder: str | Path) -> list[Path]:
    """Write ``rvm_color.png``, ``rvm_labels.png`` (uint8 label IDs) and, when drawn,
    ``ec_annotated.png`` into ``folder``; returns the files written."""
    folder = Path(folder)
    images = {"rvm_color.png": frame.color, "rvm_labels.png": frame.labels}
    if frame.annotated is not None:
        images["ec_annotated.png"] = frame.annotated
    for name, img in images.items():
        write_png(folder / name, img)
    return [folder / name for name in images]


def write_processed(frame: RvmFrame, folder: str | Path, params: IspParams) -> list[Path]:
    """What ``rvmsim process`` writes: :func:`write_frame`'s images, ``rvm_labels_preview.png``
    (labels in colour), ``fisheye_roi.png`` (the fisheye image with the region the RVM image
    shows outlined in green) and ``isp.json`` (``params``, as given for the full sensor)."""
    folder = Path(folder)
    written = write_frame(frame, folder)
    extra = {"rvm_labels_preview.png": L.colorize(frame.labels),
             "fisheye_roi.png": draw_roi(frame.fisheye.color, frame.params, frame.output)}
    for name, img in extra.items():
        write_png(folder / name, img)
    (folder / "isp.json").write_text(json.dumps(params_to_dict(params, frame.output), indent=2))
    return written + [folder / name for name in extra] + [folder / "isp.json"]


def write_evaluation(frame: RvmFrame, folder: str | Path, params: IspParams, *,
                     scene_file: str | Path, vehicle: str,
                     criteria_file: str | Path | None) -> list[Path]:
    """What ``rvmsim evaluate`` writes: :func:`write_frame`'s images and ``ec.json`` (the
    scene and criteria files, ``params`` as given for the full sensor, the ECs, judged at
    ``frame.output``: the caller passes the RVM image of record)."""
    folder = Path(folder)
    written = write_frame(frame, folder)
    doc = {"scene": str(scene_file), "vehicle": vehicle, "criteria_file": str(criteria_file or ""),
           "judged_at": [frame.output.width, frame.output.height],
           "isp": params_to_dict(params, frame.output, judged_at=frame.output),
           **frame.ec.as_dict()}
    (folder / "ec.json").write_text(json.dumps(doc, indent=2))
    return written + [folder / "ec.json"]


def write_fisheye(images: FisheyeImages, folder: str | Path, *, scene_file: str | Path,
                  vehicle: str) -> list[Path]:
    """What ``rvmsim render`` writes: ``fisheye_color.png``, ``fisheye_labels.png`` (uint8
    label IDs), ``fisheye_labels_preview.png`` (labels in colour) and ``render.json`` (the
    camera, the cube faces, the timings and the labels present)."""
    folder = Path(folder)
    pngs = {"fisheye_color.png": images.color, "fisheye_labels.png": images.labels,
            "fisheye_labels_preview.png": L.colorize(images.labels)}
    for name, img in pngs.items():
        write_png(folder / name, img)
    cam = images.camera
    present = sorted(int(i) for i in set(images.labels.ravel().tolist()))
    names = L.label_names()
    meta = {
        "scene": str(scene_file),
        "name": vehicle,
        "image_size": [cam.width, cam.height],
        "K": cam.K.tolist(),
        "D": cam.D.ravel().tolist(),
        "lens_model": cam.lens_model,
        "fov_deg": cam.fov_deg,
        "face_size_px": images.face_size,
        "faces": list(images.faces),
        "timings_s": {k: round(v, 4) for k, v in images.timings.items()},
        "labels_present": {str(i): names.get(i, "?") for i in present},
    }
    (folder / "render.json").write_text(json.dumps(meta, indent=2))
    return [folder / name for name in pngs] + [folder / "render.json"]
