"""The scene schema: one vehicle's rear-view camera, body parts and FMVSS 111 test site.

These pydantic models validate a scene document (unknown keys are errors); reading a scene
file, with one-line :class:`~rvmsim.errors.SceneError` messages naming the file, the line and
the dotted key, is :mod:`rvmsim.scene.loading`.  Paths inside a scene file (mesh files) are
resolved relative to the scene file.

Units: metres and degrees; pixels for image sizes and intrinsics.  Frame: see
:mod:`rvmsim.camera` (X toward the driver's side, Y toward the ground, Z rearward, origin on
the ground below the rearmost point of the bumper).  Heights in the vehicle and test-site
sections are given as positive heights above the ground for readability; the camera
position is a point in the scene frame, so a camera 1 m up has ``y = -1.0``.

See ``docs/scene-format.md`` for an annotated example.
"""

from __future__ import annotations

import math
from pathlib import Path
from collections.abc import Iterable
from typing import Annotated, Literal, Union

import numpy as np
from pydantic import Discriminator, Field, Tag, model_validator

from .._io import FilePathText
from . import fmvss111
from ..camera import FisheyeCamera, make_lens, rotation_from_ypr
from .display import Display
from .eol import EolSpec
from .guideline_spec import GuidelineSpec, PaintedLine
from .running_gear import RunningGearKeys
from .load_state import SceneLoadState
from .sitedefs import DEFAULT_SITE, SiteObject
from .variation import VariationSpec

__all__ = [
    "Scene",
    "CameraSpec",
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
]

from .board import PatternBoard
from .pattern import GroundPattern
from .fields import (Angle180, Metres, NonNegFloat, PositiveFloat, PositivePx, Px,
                     Rect, Rgb, Vec3, _Model)

# ---------------------------------------------------------------------------- camera
class Intrinsics(_Model):
    """Focal lengths and principal point, given in exactly one of four ways.

    * ``fx``, ``fy`` (px/rad) [, ``cx``, ``cy`` px];
    * ``K``: the 3×3 camera matrix of a ``cv2.fisheye`` calibration, pasted as is;
    * ``horizontal_fov_deg``: the lens's angle across the image width (equidistance scale);
    * ``focal_length_mm`` and ``pixel_pitch_um``.

    The principal point defaults to the image centre ((W − 1)/2, (H − 1)/2).
    """

    fx: PositivePx | None = None
    fy: PositivePx | None = None
    cx: Px | None = None
    cy: Px | None = None
    skew: Annotated[float, Field(gt=-1, lt=1)] = 0.0
    K: tuple[tuple[Px, Px, Px], tuple[Px, Px, Px], tuple[Px, Px, Px]] | None = None
    horizontal_fov_deg: Annotated[float, Field(gt=0, le=360)] | None = None
    focal_length_mm: Annotated[float, Field(gt=0, le=1000)] | None = None
    pixel_pitch_um: Annotated[float, Field(gt=0, le=1000)] | None = None

    @model_validator(mode="after")
    def _one_way(self) -> Intrinsics:
        ways = [
            self.fx is not None or self.fy is not None,
            self.K is not None,
            self.horizontal_fov_deg is not None,
            self.focal_length_mm is not None or self.pixel_pitch_um is not None,
        ]
        if sum(ways) != 1:
            raise ValueError(
                "give exactly one of: fx+fy, K, horizontal_fov_deg, focal_length_mm+pixel_pitch_um"
            )
        if ways[0] and (self.fx is None or self.fy is None):
            raise ValueError("fx and fy must both be given")
        if ways[3] and (self.focal_length_mm is None or self.pixel_pitch_um is None):
            raise ValueError("focal_length_mm needs pixel_pitch_um (and the other way round)")
        if self.K is not None:
            k = np.asarray(self.K)
            if k[0, 0] <= 0 or k[1, 1] <= 0:
                raise ValueError("K: focal lengths K[0][0], K[1][1] must be > 0")
            if k[1, 0] != 0 or k[2, 0] != 0 or k[2, 1] != 0 or k[2, 2] != 1:
                raise ValueError("K must be [[fx, s, cx], [0, fy, cy], [0, 0, 1]]")
        return self

    def resolve(self, width: int, height: int) -> tuple[float, float, float, float, float]:
        """(fx, fy, cx, cy, skew) for an image of ``width`` × ``height`` px.

        Returns
        -------
        (float, float, float, float, float)
            Focal lengths in px/rad, principal point in px, skew (cv2.fisheye's alpha).

        Convention
        ----------
        Pixel centres at integer coordinates: the default principal point is the image centre
        ((W − 1)/2, (H − 1)/2).
        """
        cx = (width - 1) / 2.0 if self.cx is None else self.cx
        cy = (height - 1) / 2.0 if self.cy is None else self.cy
        if self.K is not None:
            k = self.K
            return k[0][0], k[1][1], k[0][2], k[1][2], k[0][1] / k[0][0]
        if self.horizontal_fov_deg is not None:
            f = (width / 2.0) / math.radians(self.horizontal_fov_deg / 2.0)
            return f, f, cx, cy, self.skew
        if self.focal_length_mm is not None and self.pixel_pitch_um is not None:
            f = self.focal_length_mm * 1000.0 / self.pixel_pitch_um
            return f, f, cx, cy, self.skew
        assert self.fx is not None and self.fy is not None
        return self.fx, self.fy, cx, cy, self.skew


class Lens(_Model):
    """Lens model by name: ``equidistance`` (r = f·θ), ``kannala_brandt`` (k1..k4 as in
    cv2.fisheye), or one registered with :func:`rvmsim.camera.register_lens_model`."""

    #: A registered lens model's name (:data:`rvmsim.camera.LENS_MODELS`).
    model: str = "equidistance"
    k: tuple[float, float, float, float] | None = None
    fov_deg: Annotated[float, Field(gt=0, le=360)] = 190.0

    @model_validator(mode="after")
    def _k_matches_model(self) -> Lens:
        make_lens(self.model, self.k)  # ValueError: an unknown model, or k that does not fit
        return self


class Mount(_Model):
    """Camera pose: optical centre in the scene frame (metres) and mount angles (degrees)."""

    position: Vec3
    yaw_deg: Angle180 = 0.0
    pitch_deg: Annotated[float, Field(ge=-90, le=90)] = 0.0
    roll_deg: Angle180 = 0.0


class CameraSpec(_Model):
    image_size: tuple[Annotated[int, Field(gt=0)], Annotated[int, Field(gt=0)]]
    intrinsics: Intrinsics
    lens: Lens = Lens()
    mount: Mount

    def to_camera(self) -> FisheyeCamera:
        w, h = self.image_size
        fx, fy, cx, cy, skew = self.intrinsics.resolve(w, h)
        m = self.mount
        return FisheyeCamera(
            width=w,
            height=h,
            fx=fx,
            fy=fy,
            cx=cx,
            cy=cy,
            k=self.lens.k or (0.0, 0.0, 0.0, 0.0),
            skew=skew,
            fov_deg=self.lens.fov_deg,
            rotation=rotation_from_ypr(m.yaw_deg, m.pitch_deg, m.roll_deg),
            position=np.asarray(m.position, dtype=np.float64),
            lens_model=self.lens.model,
        )


# ---------------------------------------------------------------------------- vehicle
class BlockPart(_Model):
    """A parametric body part: a swept block with a curved rear face.

    In plan view the rear face is ``z(x) = -setback - sweep · (2x / width)²``; it rises from
    ``bottom`` to ``top`` (heights above ground, metres), leaning forward by ``lean_deg``
    (0 = vertical; a tailgate or rear window leans forward with height), and the top surface
    reaches ``depth`` metres forward from the rear face.
    """

    width: PositiveFloat
    bottom: NonNegFloat
    top: PositiveFloat
    depth: PositiveFloat
    setback: NonNegFloat = 0.0
    sweep: NonNegFloat = 0.0
    lean_deg: Annotated[float, Field(ge=-45, le=80)] = 0.0
    color: Rgb | None = None

    @model_validator(mode="after")
    def _top_above_bottom(self) -> BlockPart:
        if self.top <= self.bottom:
            raise ValueError(f"top ({self.top}) must be above bottom ({self.bottom})")
        return self


class MeshPart(_Model):
    """A body part from a mesh file (STL/OBJ/PLY/glTF/GLB, anything trimesh loads).

    The file's coordinates are scaled by ``units`` to metres, rotated by
    ``rotation_deg`` = (yaw, pitch, roll) with the camera's convention, then translated by
    ``translation`` (scene frame, metres).  ``mesh`` is relative to the scene file.
    """

    mesh: FilePathText
    units: Literal["m", "mm", "cm", "in"] = "m"
    translation: Vec3 = (0.0, 0.0, 0.0)
    rotation_deg: tuple[Angle180, Angle180, Angle180] = (0.0, 0.0, 0.0)
    color: Rgb | None = None

    @property
    def scale(self) -> float:
        return {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254}[self.units]

    def transform(self) -> np.ndarray:
        """(4, 4) file-to-scene transform (scale, then rotate, then translate).

        Convention
        ----------
        Maps homogeneous points of the mesh file (in ``units``) to the scene frame, metres;
        ``rotation_deg`` = (yaw, pitch, roll) as :func:`~rvmsim.camera.rotation_from_ypr`.
        """
        t = np.eye(4)
        t[:3, :3] = rotation_from_ypr(*self.rotation_deg) * self.scale
        t[:3, 3] = self.translation
        return t


def _part_kind(v: object) -> str:
    if isinstance(v, dict):
        return "mesh" if "mesh" in v else "block"
    return "mesh" if isinstance(v, MeshPart) else "block"


Part = Annotated[
    Union[Annotated[BlockPart, Tag("block")], Annotated[MeshPart, Tag("mesh")]],
    Discriminator(_part_kind),
]


class Vehicle(RunningGearKeys):
    paint: Rgb = (0.75, 0.75, 0.78)
    bumper: Part
    garnish: Part | None = None
    trunk: Part | None = None
    extra: list[MeshPart] = []
    #: Overall width (metres) that site definitions place their objects by
    #: (:mod:`rvmsim.scene.sitedefs`); None: the widest body part.  Not part of the render
    #: key (a site's placed objects are).
    width: PositiveFloat | None = Field(default=None, exclude=True)


# ---------------------------------------------------------------------------- test site
class TestObject(_Model):
    """Override for one FMVSS test object: its position and whether it is placed."""

    __test__ = False  # not a pytest class
    position: tuple[Metres, Metres] | None = None  # (x, z) metres
    enabled: bool = True


StripeFacing = Union[Literal["vehicle_centreline", "vehicle", "camera"], Angle180]


class Guidelines(_Model):
    """Fixed trajectory guidelines painted on the ground.

    Two side lines at ``side_x`` (lateral positions, metres) running from ``side_z[0]`` to
    ``side_z[1]`` behind the bumper, and cross lines at distances ``cross_z`` (numbered 1, 2, …
    from the bumper) spanning the side lines.
    """

    enabled: bool = True
    side_x: tuple[Metres, Metres] = (-0.9, 0.9)
    side_z: tuple[NonNegFloat, PositiveFloat] = (0.2, 3.0)
    cross_z: list[PositiveFloat] = [0.5, 1.0, 2.0, 3.0]
    line_width: PositiveFloat = 0.05
    color: Rgb = (0.95, 0.85, 0.1)

    @model_validator(mode="after")
    def _check(self) -> Guidelines:
        if self.side_x[0] >= self.side_x[1]:
            raise ValueError("side_x must be [negative-side x, positive-side x], increasing")
        if self.side_z[0] >= self.side_z[1]:
            raise ValueError("side_z must be [start, end] with start < end")
        if len(self.cross_z) > 19:
            raise ValueError("at most 19 cross lines")
        if list(self.cross_z) != sorted(self.cross_z):
            raise ValueError("cross_z must be increasing (line 1 nearest the bumper)")
        return self


class TestSite(_Model):
    """The FMVSS 111 layout (defaults in :mod:`rvmsim.scene.fmvss111`) plus customer fixtures.

    ``fmvss: false`` leaves the FMVSS test objects A–G and the guidelines out (a minimal
    camera-plus-board scene); ``objects`` and ``guidelines`` may then not be given.
    """

    __test__ = False
    fmvss: bool = True
    # The FMVSS values come from the bundled site file, read on first use.
    object_height: PositiveFloat = Field(
        default_factory=lambda: fmvss111.site_values()["OBJECT_HEIGHT_M"])
    object_diameter: PositiveFloat = Field(
        default_factory=lambda: fmvss111.site_values()["OBJECT_DIAMETER_M"])
    stripe_width: PositiveFloat = Field(
        default_factory=lambda: fmvss111.site_values()["STRIPE_WIDTH_M"])
    lower_patch_height: PositiveFloat = Field(
        default_factory=lambda: fmvss111.site_values()["LOWER_PATCH_HEIGHT_M"])
    position_reference: Literal["centre", "surface"] = Field(
        default_factory=lambda: fmvss111.site_values()["OBJECT_POSITION_REFERENCE"])
    vertical_stripe_facing: StripeFacing = fmvss111.VERTICAL_STRIPE_FACING  # type: ignore[assignment]
    objects: dict[Literal["A", "B", "C", "D", "E", "F", "G"], TestObject] = {}
    guidelines: Guidelines = Guidelines()
    board: PatternBoard = PatternBoard()
    ground_patterns: list[GroundPattern] = []
    ground_size: PositiveFloat = 60.0
    ground_color: Rgb = (0.42, 0.42, 0.42)
    #: The site this is (:mod:`rvmsim.scene.sitedefs`) and, for a site other than FMVSS
    #: 111's, its placed objects (set by :func:`rvmsim.scene.site_scene`, not a YAML key).
    site: str = DEFAULT_SITE
    site_objects: tuple[SiteObject, ...] = ()
    #: Lines painted on the ground to check the guidelines against (set by
    #: :mod:`rvmsim.guidelines.check`, not a YAML key).
    painted_lines: tuple[PaintedLine, ...] = ()

    @model_validator(mode="after")
    def _check(self) -> TestSite:
        if not self.fmvss:
            given = sorted({"objects", "guidelines"} & self.model_fields_set)
            if given:
                raise ValueError(f"fmvss: false has no FMVSS objects or guidelines "
                                 f"(remove {', '.join(given)})")
        if self.stripe_width >= self.object_height:
            raise ValueError("stripe_width must be smaller than object_height")
        if self.lower_patch_height >= self.object_height:
            raise ValueError("lower_patch_height must be smaller than object_height")
        if self.stripe_width >= math.pi * self.object_diameter:
            raise ValueError("stripe_width must be smaller than the object circumference")
        return self

    def object_centre(self, letter: str) -> tuple[float, float] | None:
        """(x, z) of the axis of object ``letter`` in metres, or None when it is disabled.

        Convention
        ----------
        Scene frame on the ground plane; None for every object when ``fmvss`` is false.
        With ``position_reference: surface`` the given
        position is the object's surface nearest the car, so the axis lies a radius further
        rearward (+Z).
        """
        if not self.fmvss:
            return None
        override = self.objects.get(letter)  # type: ignore[call-overload]
        if override is not None and not override.enabled:
            return None
        x, z = fmvss111.site_values()["OBJECT_POSITIONS_M"][letter]
        if override is not None and override.position is not None:
            x, z = override.position
        if self.position_reference == "surface":
            z += self.object_diameter / 2.0
        return (x, z)


class RenderSettings(_Model):
    """Renderer knobs.

    ``face_size_px``: cube face resolution (None: automatic, ``oversample`` face pixels per
    fisheye pixel where the faces are least dense).  Nearest label sampling puts a label
    border within 0.5 / ``oversample`` px of its true place.  ``color_filter``: ``area``
    (the default: each fisheye pixel averaged over its footprint, so edge sharpness does not
    depend on ``oversample``) or ``bilinear`` (one tap per fisheye pixel, a little faster;
    a denser atlas then aliases: checker corners 0.15 px RMS at oversample 1.5, 0.22 px at
    3.5, against 0.06 px at both with ``area``).
    """

    face_size_px: Annotated[int, Field(ge=16, le=8192)] | None = None
    color_filter: Literal["bilinear", "area"] = "area"
    oversample: Annotated[float, Field(ge=0.5, le=4.0)] = 1.5
    max_face_size_px: Annotated[int, Field(ge=16, le=8192)] = 4096
    sky_color: Rgb = (0.62, 0.76, 0.92)


def _spec_kind(v: object) -> str:
    return "file" if isinstance(v, str) else "spec"


#: The scene's ``guidelines:``: a mapping, or a spec file's path (the tags are not part of
#: error keys: :data:`rvmsim.scene.loading._TAGS`).
GuidelineSpecOrFile = Annotated[
    Union[Annotated[GuidelineSpec, Tag("spec")], Annotated[FilePathText, Tag("file")]],
    Discriminator(_spec_kind),
]


class Scene(_Model):
    """One vehicle at the test site.  Build with :func:`load_scene` or :func:`scene_from_dict`.

    ``vehicle`` may be absent or null: a camera with no body in view (a camera on a bench in
    front of a calibration board, :attr:`TestSite.fmvss` false).
    """

    name: str
    description: str = ""
    camera: CameraSpec
    vehicle: Vehicle | None = None
    test_site: TestSite = Field(default_factory=TestSite)
    render: RenderSettings = RenderSettings()
    #: The display the driver sees (EC 1-6, :mod:`rvmsim.scene.display`); None: the criteria
    #: file's, else the defaults.  Not part of the render cache's key.
    display: Display | None = Field(default=None, exclude=True)
    #: Production variation (:mod:`rvmsim.robust`); not part of the render cache's key.
    variation: VariationSpec | None = Field(default=None, exclude=True)
    #: The body under a load (:mod:`rvmsim.scene.load_state`); None: unloaded.  Left out of
    #: dumps so that unloaded scenes keep their render keys; the render key adds it
    #: (:func:`rvmsim.render.scene_key`).
    load_state: SceneLoadState | None = Field(default=None, exclude=True)
    #: The end-of-line station's target (:mod:`rvmsim.scene.eol`, ``rvmsim eol``); not part
    #: of the render cache's key.
    eol: EolSpec | None = Field(default=None, exclude=True)
    #: The test sites the scene is judged at (:mod:`rvmsim.scene.sitedefs`): bundled names or
    #: site files (relative to the scene file); not part of the render key (each site's
    #: scene has its own).
    sites: Annotated[list[FilePathText], Field(min_length=1, max_length=8)] = Field(
        default=[DEFAULT_SITE], exclude=True)
    #: The parking guidelines drawn over the picture (:mod:`rvmsim.guidelines`): a mapping,
    #: or a spec file relative to the scene file (read when the scene loads); None: the
    #: bundled default.  Not part of the render key.
    guidelines: GuidelineSpecOrFile | None = Field(default=None, exclude=True)
    #: Directory that relative paths in the scene are resolved against (not a YAML key).
    base_dir: str = Field(default=".", exclude=True)
    #: The file the scene was read from, for messages (not a YAML key).
    source: str = Field(default="<dict>", exclude=True)

    @property
    def guidelines_shown(self) -> bool:
        """Whether the scene has the painted guidelines (enabled, and an FMVSS site)."""
        return self.test_site.fmvss and self.test_site.guidelines.enabled

    def with_mount(self, position_m: Iterable[float], yaw_deg: float, pitch_deg: float,
                   roll_deg: float) -> Scene:
        """A copy of the scene with the camera mounted at ``position_m`` (m, scene frame)
        and turned to ``yaw_deg``, ``pitch_deg``, ``roll_deg`` (degrees, the ``mount``
        section's angles); nothing else changes (a load state keeps its pivot)."""
        mount = self.camera.mount.model_copy(update={
            "position": tuple(float(p) for p in position_m), "yaw_deg": float(yaw_deg),
            "pitch_deg": float(pitch_deg), "roll_deg": float(roll_deg)})
        return self.model_copy(update={"camera": self.camera.model_copy(
            update={"mount": mount})})

    def fisheye_camera(self) -> FisheyeCamera:
        """The rear-view camera as a :class:`~rvmsim.camera.FisheyeCamera`: at its mount
        pose, moved with the body under ``load_state`` when there is one."""
        cam = self.camera.to_camera()
        if self.load_state is None:
            return cam
        return self.load_state.camera(cam, self.camera.mount.position)

    def body_motion(self) -> np.ndarray | None:
        """The (4, 4) rigid motion of the vehicle's parts under ``load_state`` (scene frame,
        m; :func:`~rvmsim.scene.load_state.body_motion`), or None when unloaded."""
        if self.load_state is None:
            return None
        return self.load_state.motion(self.camera.mount.position)

    def resolve_path(self, path: str) -> Path:
        """A path from the scene file, made absolute relative to the scene file's folder."""
        p = Path(path).expanduser()
        return p if p.is_absolute() else (Path(self.base_dir) / p).resolve()
