"""The scene: YAML schema (camera, vehicle, FMVSS No. 111 test site), loading, meshes and
landmarks.

Modules: :mod:`.schema` (pydantic models), :mod:`.loading` (scene files → Scene),
:mod:`.load_state` (the body under a load), :mod:`.primitives` (mesh primitives,
:class:`Part`), :mod:`.site` (the test site's surfaces), :mod:`.meshes`
(:func:`build_parts`: every labelled surface), :mod:`.landmarks` (known 3D points),
:mod:`.fmvss111` (the standard's dimensions), :mod:`.eol` and :mod:`.station` (the
end-of-line station's target and the station as a scene).
"""

from __future__ import annotations

from .schema import (
    Scene,
    CameraSpec,
    Intrinsics,
    Lens,
    Mount,
    BlockPart,
    MeshPart,
    Vehicle,
    TestSite,
    TestObject,
    Guidelines,
    PatternBoard,
    GroundPattern,
    RenderSettings,
)
from .display import RVM_IMAGE_OF_RECORD_PX, Display
from .load_state import SceneLoadState, body_motion, MAX_LOAD_HEIGHT_MM, MAX_LOAD_PITCH_DEG
from .variation import (
    VariationSpec,
    MountTolerance,
    AxisSpec,
    LoadStateSpec,
    MOUNT_AXES,
)
from .eol import EolSpec, EolPose, BOARD_TARGET
from .guideline_spec import (GuidelineSpec, DistanceMark, WidthLines, TrajectoryLines,
                             PaintedLine)
from .station import station_scene, station_target, eol_problem
from .compensation import CompensationSpec, StationSpec, COMPENSABLE_PARAMS, DEFAULT_RANGES
from .loading import (
    FOCAL_FACTORS,
    camera_problem,
    load_scene,
    read_scene_document,
    scene_from_dict,
    absolute_mesh_paths,
    mesh_parts,
    scene_site_entry,
    load_guideline_spec,
)
from .primitives import Part, cylinder_side, disk, swept_block, quad
from .site import (
    stripe_azimuth_deg,
    pattern_point,
    board_point,
    board_frame,
    pattern_axes,
    pattern_shade,
    GUIDELINE_LIFT_M,
    BOARD_LIFT_M,
    PATTERN_LIFT_M,
)
from .sitedefs import (
    SiteDefinition,
    SiteObject,
    SiteError,
    BUNDLED_SITES,
    DEFAULT_SITE,
    load_site,
    bundled_site,
    site_definition,
    is_site_file,
)
from .meshes import build_parts
from .placement import scene_site, scene_sites, scene_vehicle_width, site_scene
from .landmarks import Landmark, CheckerCorner, site_landmarks, checker_corners

__all__ = [
    "Scene",
    "CameraSpec",
    "FOCAL_FACTORS",
    "camera_problem",
    "Intrinsics",
    "Lens",
    "Mount",
    "BlockPart",
    "MeshPart",
    "Vehicle",
    "TestSite",
    "TestObject",
    "Guidelines",
    "PatternBoard",
    "GroundPattern",
    "RenderSettings",
    "Display",
    "RVM_IMAGE_OF_RECORD_PX",
    "SceneLoadState",
    "body_motion",
    "MAX_LOAD_HEIGHT_MM",
    "MAX_LOAD_PITCH_DEG",
    "VariationSpec",
    "MountTolerance",
    "AxisSpec",
    "LoadStateSpec",
    "MOUNT_AXES",
    "EolSpec",
    "EolPose",
    "BOARD_TARGET",
    "station_scene",
    "station_target",
    "eol_problem",
    "CompensationSpec",
    "StationSpec",
    "COMPENSABLE_PARAMS",
    "DEFAULT_RANGES",
    "load_scene",
    "read_scene_document",
    "scene_from_dict",
    "absolute_mesh_paths",
    "mesh_parts",
    "Part",
    "Landmark",
    "CheckerCorner",
    "build_parts",
    "SiteDefinition",
    "SiteObject",
    "SiteError",
    "BUNDLED_SITES",
    "DEFAULT_SITE",
    "load_site",
    "bundled_site",
    "site_definition",
    "scene_site",
    "scene_sites",
    "site_scene",
    "scene_vehicle_width",
    "is_site_file",
    "scene_site_entry",
    "load_guideline_spec",
    "GuidelineSpec",
    "DistanceMark",
    "WidthLines",
    "TrajectoryLines",
    "PaintedLine",
    "site_landmarks",
    "checker_corners",
    "stripe_azimuth_deg",
    "pattern_point",
    "board_point",
    "board_frame",
    "pattern_axes",
    "pattern_shade",
    "cylinder_side",
    "disk",
    "swept_block",
    "quad",
    "GUIDELINE_LIFT_M",
    "BOARD_LIFT_M",
    "PATTERN_LIFT_M",
]
