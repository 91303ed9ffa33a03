"""rvmsim: tune a rear-view-monitoring camera's ISP from the vehicle's design data.

Data flows one way: scene (YAML) → meshes → fisheye images (rendered once) → [ISP map →
RVM image → ECs] per candidate → run store → report.  One subpackage per stage:
:mod:`rvmsim.camera`, :mod:`rvmsim.scene`, :mod:`rvmsim.render`, :mod:`rvmsim.isp`,
:mod:`rvmsim.criteria`, :mod:`rvmsim.robust`, :mod:`rvmsim.search` (space, strategies,
tuning config), :mod:`rvmsim.runs` (run model, store, folders), :mod:`rvmsim.tune`,
:mod:`rvmsim.batch`, :mod:`rvmsim.pose` (the mount pose in a capture),
:mod:`rvmsim.validate`, :mod:`rvmsim.eol` (the end-of-line station),
:mod:`rvmsim.report`; :mod:`rvmsim.pipeline`
joins render, ISP and ECs, and :mod:`rvmsim.storage` holds what stores and locks share.  The main entry
points are importable from here (lazily: ``import rvmsim`` starts no OpenGL).

Examples
--------
A scene, its fisheye frame (rendered once; here at a quarter of the sensor) and the RVM
image and ECs under the paper's default ISP parameters:

>>> import rvmsim
>>> scene = rvmsim.load_scene("scenes/vehicle_a.yaml")
>>> scene.name
'Vehicle A (sedan)'
>>> camera = scene.fisheye_camera().scaled(0.25)
>>> images = rvmsim.render_fisheye(scene, camera=camera)
>>> images.color.shape, images.labels.shape
((240, 320, 3), (240, 320))
>>> params = rvmsim.IspParams().for_input_scale(0.25)      # Table 2's defaults, RAD scaled
>>> frame = rvmsim.evaluate_params(images, params, rvmsim.OutputSpec(320, 180))
>>> frame.color.shape, frame.labels.shape      # the RVM image and its exact labels
((180, 320, 3), (180, 320))
>>> frame.annotated.ndim                         # the ECs drawn on it, with a legend panel
3
>>> frame.ec.items[0].id, len(frame.ec.items)
('1-1', 11)

A short tuning run (every trial goes into ``run/run.sqlite``; ``best/`` and ``top/`` hold the
results) and its review report:

>>> request = rvmsim.TuneRequest(("scenes/vehicle_a.yaml",), strategy="random", budget=40)
>>> result = rvmsim.tune_scene(request, run_dir)
>>> result.outcome.evaluated
40
>>> 0.0 <= result.outcome.best.score <= 1.0
True
>>> rvmsim.write_report(run_dir).name
'report.html'

Errors in user files are :class:`InputFileError` s naming the file, the key and the line:

>>> try:
...     rvmsim.scene_from_dict({"name": "x"}, source="bad.yaml")
... except rvmsim.SceneError as err:
...     print(err)
bad.yaml: camera: missing required key
"""

from __future__ import annotations

import importlib
from typing import Any

from .errors import (
    CriteriaError,
    InputFileError,
    ParamsFileError,
    RvmsimError,
    SceneError,
    SweepFileError,
    TuningConfigError,
    VariationError,
)

from ._version import __version__

#: Public name → (module, name there).  Resolved on first use, so importing rvmsim stays
#: cheap and never starts OpenGL.  Some names differ from the function's own: the
#: subpackages ``rvmsim.tune`` and ``rvmsim.validate`` keep their names, so their main
#: functions are ``tune_scene`` and ``validate_capture`` here.
_LAZY: dict[str, tuple[str, str]] = {
    # scene and camera
    "Scene": ("rvmsim.scene", "Scene"),
    "load_scene": ("rvmsim.scene", "load_scene"),
    "scene_from_dict": ("rvmsim.scene", "scene_from_dict"),
    "FisheyeCamera": ("rvmsim.camera", "FisheyeCamera"),
    "rotation_from_ypr": ("rvmsim.camera", "rotation_from_ypr"),
    # render
    "FisheyeImages": ("rvmsim.render", "FisheyeImages"),
    "render_fisheye": ("rvmsim.render", "render_fisheye"),
    "cached_render": ("rvmsim.render", "cached_render"),
    # ISP
    "IspParams": ("rvmsim.isp", "IspParams"),
    "OutputSpec": ("rvmsim.isp", "OutputSpec"),
    "process": ("rvmsim.isp", "process"),
    "load_params": ("rvmsim.isp", "load_params"),
    # criteria
    "Criteria": ("rvmsim.criteria", "Criteria"),
    "EcResult": ("rvmsim.criteria", "EcResult"),
    "evaluate": ("rvmsim.criteria", "evaluate"),
    "load_criteria": ("rvmsim.criteria", "load_criteria"),
    "default_criteria": ("rvmsim.criteria", "default_criteria"),
    # scene → RVM frame → ECs
    "RvmFrame": ("rvmsim.pipeline", "RvmFrame"),
    "evaluate_params": ("rvmsim.pipeline", "evaluate_params"),
    "render_rvm": ("rvmsim.pipeline", "render_rvm"),
    "make_evaluator": ("rvmsim.pipeline", "make_evaluator"),
    # production variation
    "load_variation": ("rvmsim.robust", "load_variation"),
    "draw_samples": ("rvmsim.robust", "draw_samples"),
    "robustness": ("rvmsim.robust", "robustness"),
    "RobustnessSettings": ("rvmsim.robust", "RobustnessSettings"),
    # tuning
    "tune_scene": ("rvmsim.tune", "tune"),
    "TuneRequest": ("rvmsim.tune", "TuneRequest"),
    "RunOptions": ("rvmsim.tune", "RunOptions"),
    "resume_run": ("rvmsim.tune", "resume"),
    "TuningConfig": ("rvmsim.search", "TuningConfig"),
    "load_tuning_config": ("rvmsim.search", "load_tuning_config"),
    "STRATEGIES": ("rvmsim.search", "STRATEGIES"),
    "RunStore": ("rvmsim.runs", "RunStore"),
    # batch and design sweeps
    "load_sweep": ("rvmsim.batch", "load_sweep"),
    "run_sweep": ("rvmsim.batch", "run_sweep"),
    # validation against real captures
    "validate_capture": ("rvmsim.validate", "validate"),
    "load_capture": ("rvmsim.pose", "load_capture"),
    # the end-of-line station
    "run_station": ("rvmsim.eol", "run_station"),
    "StationSettings": ("rvmsim.eol", "StationSettings"),
    # reports
    "write_report": ("rvmsim.report", "write_report"),
}

__all__ = [
    "RvmsimError",
    "InputFileError",
    "SceneError",
    "CriteriaError",
    "TuningConfigError",
    "SweepFileError",
    "ParamsFileError",
    "VariationError",
    *_LAZY,
]


def __getattr__(name: str) -> Any:
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'rvmsim' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
