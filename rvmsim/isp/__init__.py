"""The ISP model: fisheye correction and virtual pan-tilt-zoom (the paper's 14 parameters)."""

from __future__ import annotations

from .core import (
    IspParams,
    OutputSpec,
    ParamSpec,
    PARAM_SPECS,
    TUNED_BY_DEFAULT,
    IspMap,
    build_map,
    build_map_exact,
    map_nodes,
    MapNodes,
    RayCache,
    apply_map,
    process,
    roi_outline,
    draw_roi,
    input_to_output,
    load_params,
    params_to_dict,
)

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
    "RayCache",
    "apply_map",
    "process",
    "roi_outline",
    "draw_roi",
    "input_to_output",
    "load_params",
    "params_to_dict",
]
