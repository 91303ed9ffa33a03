"""The ISP model: fisheye correction and virtual pan-tilt-zoom (the paper's 14 parameters).

Modules: :mod:`.params` (the parameters, the output image, params files), :mod:`.exact` (the
output → input map's formulas, evaluated exactly), :mod:`.map` (the fast, error-controlled
map and the remap), :mod:`.roi` (the region of interest and the inverse map).
"""

from __future__ import annotations

from .params import (
    IspParams,
    OutputSpec,
    ParamSpec,
    PARAM_SPECS,
    TUNED_BY_DEFAULT,
    load_params,
    params_judged_at,
    params_to_dict,
)
from .exact import IspMap, build_map_exact
from .map import (
    InputWarp,
    build_map,
    map_nodes,
    MapNodes,
    RayCache,
    apply_map,
    remap_xy,
    process,
)
from .roi import roi_outline, draw_roi, input_to_output, input_to_plane

__all__ = [
    "IspParams",
    "OutputSpec",
    "ParamSpec",
    "PARAM_SPECS",
    "TUNED_BY_DEFAULT",
    "IspMap",
    "build_map",
    "build_map_exact",
    "map_nodes",
    "MapNodes",
    "InputWarp",
    "RayCache",
    "apply_map",
    "remap_xy",
    "process",
    "roi_outline",
    "draw_roi",
    "input_to_output",
    "input_to_plane",
    "load_params",
    "params_judged_at",
    "params_to_dict",
]
