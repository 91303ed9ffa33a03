"""The evaluation path: ISP parameters → RVM colour and label images → ECs → annotated image.

:func:`evaluate_params` is the one place this is done, for rendered fisheye images: tuning's
results, the review report, ``rvmsim evaluate`` and ``process``, validation and the sweep
all call it.  :func:`render_rvm` renders a scene first (at a fraction of its sensor, if
asked).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .criteria import Criteria, EcResult, IspView, default_criteria, evaluate, scene_context
from .criteria import annotate as annotate_ecs
from .isp import IspParams, OutputSpec, draw_roi, params_to_dict, process
from .render import FisheyeImages, render_fisheye
from .scene import Scene

__all__ = ["RvmFrame", "evaluate_params", "rvm_color", "render_rvm", "write_frame",
           "write_processed", "write_evaluation", "write_fisheye"]


@dataclass(frozen=True)
class RvmFrame:
    """A rendered fisheye frame, its RVM images under one ISP parameter set, and their ECs.

    ``params`` are the parameters as applied to ``fisheye`` (RAD and shifts scaled when the
    fisheye was rendered at a fraction of the sensor).  ``color`` is (H, W, 3) uint8 and
    ``labels`` (H, W) uint8 at ``output``'s size; ``ec`` the ECs measured on ``labels``;
    ``annotated`` the measurements drawn on ``color`` with a results panel (None when not
    asked for).
    """

    fisheye: FisheyeImages
    params: IspParams
    output: OutputSpec
    color: np.ndarray
    labels: np.ndarray
    ec: EcResult
    annotated: np.ndarray | None = None


def evaluate_params(images: FisheyeImages, params: IspParams, output: OutputSpec,
                    criteria: Criteria | None = None, *, annotate: bool = True) -> RvmFrame:
    """Run the ISP on rendered fisheye images and evaluate the RVM image.

    Parameters
    ----------
    images : FisheyeImages
        Rendered fisheye colour and label images (``images.scene``, when set, is the scene
        that ECs needing its geometry or display read).
    params : IspParams
        ISP parameters for ``images``' size.
    output : OutputSpec
        RVM image size (px) and mirroring.
    criteria : Criteria, optional
        Default: the paper's (:func:`rvmsim.criteria.default_criteria`).
    annotate : bool
        Also draw the ECs (:func:`rvmsim.criteria.annotate`).

    Returns
    -------
    RvmFrame
    """
    criteria = criteria if criteria is not None else default_criteria()
    color, labels = process(images.color, images.labels, params, output)
    assert color is not None and labels is not None  # process returns what it is given
    # ECs that need the scene or the map (e.g. 1-5, 1-6, 6-1) read them from here
    context = scene_context(images.scene, images.camera, images.labels)
    isp = IspView(params, (images.labels.shape[1], images.labels.shape[0]), output)
    ec = evaluate(labels, criteria, context=context, isp=isp)
    drawn = annotate_ecs(color, labels, ec) if annotate else None
    return RvmFrame(fisheye=images, params=params, output=output, color=color, labels=labels,
                    ec=ec, annotated=drawn)


def rvm_color(images: FisheyeImages, params: IspParams, output: OutputSpec) -> np.ndarray:
    """Only the RVM colour image (no labels, no ECs): (H, W, 3) uint8 at ``output``'s size,
    e.g. the same view at a display's size or a thumbnail of another candidate."""
    color, _ = process(images.color, None, params, output)
    assert color is not None
    return color


def render_rvm(scene: Scene, params: IspParams, output: OutputSpec = OutputSpec(), *,
               criteria: Criteria | None = None, scale: float = 1.0, annotate: bool = False,
               progress: bool = False) -> RvmFrame:
    """Render ``scene`` (at ``scale`` of its sensor size) and evaluate ``params`` on it
    (:func:`evaluate_params`).

    Parameters
    ----------
    scene : Scene
    params : IspParams
        ISP parameters for the full-size sensor.
    output : OutputSpec
        RVM image size and mirroring.
    criteria : Criteria, optional
        Default: the paper's.
    scale : float
        Fraction of the sensor to render (RAD and the shifts follow, the view stays).
    annotate : bool
        Also draw the ECs.
    progress : bool
        Progress bar while rendering.
    """
    cam = scene.fisheye_camera()
    if scale != 1.0:
        cam = cam.scaled(scale)
        params = params.for_input_scale(cam.width / scene.camera.image_size[0])
    images = render_fisheye(scene, camera=cam, progress=progress)
    return evaluate_params(images, params, output, criteria, annotate=annotate)


def write_frame(frame: RvmFrame, folder: str | Path) -> list[Path]:
    """Write ``rvm_color.png``, ``rvm_labels.png`` (uint8 label IDs) and, when drawn,
    ``ec_annotated.png`` into ``folder``; returns the files written."""
    from ._io import write_png

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
    from . import labels as L
    from ._io import write_png

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
    scene and criteria files, ``params`` as given for the full sensor, the ECs)."""
    folder = Path(folder)
    written = write_frame(frame, folder)
    doc = {"scene": str(scene_file), "vehicle": vehicle, "criteria_file": str(criteria_file or ""),
           "isp": params_to_dict(params, frame.output), **frame.ec.as_dict()}
    (folder / "ec.json").write_text(json.dumps(doc, indent=2))
    return written + [folder / "ec.json"]


def write_fisheye(images: FisheyeImages, folder: str | Path, *, scene_file: str | Path,
                  vehicle: str) -> list[Path]:
    """What ``rvmsim render`` writes: ``fisheye_color.png``, ``fisheye_labels.png`` (uint8
    label IDs), ``fisheye_labels_preview.png`` (labels in colour) and ``render.json`` (the
    camera, the cube faces, the timings and the labels present)."""
    from . import labels as L
    from ._io import write_png

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
        "fov_deg": cam.fov_deg,
        "face_size_px": images.face_size,
        "faces": list(images.faces),
        "timings_s": {k: round(v, 4) for k, v in images.timings.items()},
        "labels_present": {str(i): names.get(i, "?") for i in present},
    }
    (folder / "render.json").write_text(json.dumps(meta, indent=2))
    return [folder / name for name in pngs] + [folder / "render.json"]
