"""Reading scene files: YAML → validated :class:`~rvmsim.scene.Scene`.

A scene file is read with ``yaml.safe_load`` and validated by the models of
:mod:`rvmsim.scene.schema`.  Every problem becomes a :class:`~rvmsim.errors.SceneError` that
names the file, the line and the dotted key.  Paths inside a scene file (mesh files) are
resolved relative to the scene file.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from .._io import (KeyPath, image_size_problem, input_error_from_validation, key_lines,
                   line_of, parse_yaml, parse_yaml_mapping, read_text)
from ..errors import SceneError
from .guideline_spec import GuidelineSpec
from .schema import CameraSpec, MeshPart, Scene
from .station import eol_problem
from .sitedefs import BUNDLED_SITES, SiteDefinition, SiteError, is_site_file, site_definition

__all__ = [
    "scene_site_entry",
    "load_guideline_spec",
    "load_scene",
    "read_scene_document",
    "scene_from_dict",
    "absolute_mesh_paths",
    "mesh_parts",
    "camera_problem",
    "FOCAL_FACTORS",
]

#: Discriminator tags of the vehicle parts, which pydantic puts into error locations.
_TAGS = frozenset({"block", "mesh", "spec", "file"})


def scene_from_dict(
    data: object, *, base_dir: str | Path = ".", source: str = "<dict>", text: str | None = None
) -> Scene:
    """Validate a parsed scene document.

    Parameters
    ----------
    data : dict
        The document (as ``yaml.safe_load`` gives it).
    base_dir : path
        Folder that relative paths in the scene are resolved against.
    source : str
        Name used in error messages.
    text : str, optional
        The YAML text, to give line numbers in error messages.

    Raises
    ------
    SceneError
        For any invalid or missing key, or a missing mesh file.
    """
    if not isinstance(data, dict):
        raise SceneError(source, "", "a scene file must be a YAML mapping (key: value)")
    try:
        scene = Scene.model_validate(
            {**data, "base_dir": str(Path(base_dir).resolve()), "source": source}
        )
    except ValidationError as err:
        raise input_error_from_validation(err, source, key_lines(text or ""), SceneError,
                                          _TAGS) from None
    lines = key_lines(text or "")
    bad = camera_problem(scene.camera)
    if bad is not None:
        key, message = bad
        raise SceneError(source, key, message, line_of(lines, tuple(key.split("."))))
    try:
        scene.fisheye_camera()
    except ValueError as err:
        raise SceneError(source, "camera", str(err), lines.get(("camera",))) from None
    bad = eol_problem(scene)
    if bad is not None:
        key, message = bad
        raise SceneError(source, key, message, line_of(lines, tuple(key.split("."))))
    _check_sites(scene, lines)
    if isinstance(scene.guidelines, str):
        spec_path = scene.resolve_path(scene.guidelines)
        if not spec_path.is_file():
            raise SceneError(source, "guidelines", f"guideline spec file not found: {spec_path}",
                             lines.get(("guidelines",)))
        scene = scene.model_copy(update={"guidelines": load_guideline_spec(spec_path)})
    for key, part in mesh_parts(scene):
        path = scene.resolve_path(part.mesh)
        if not path.is_file():
            loc = tuple(int(p) if p.isdigit() else p for p in key.split("."))
            raise SceneError(
                source, key, f"mesh file not found: {path}", lines.get(loc)
            )
    return scene


def load_guideline_spec(path: str | Path) -> GuidelineSpec:
    """Read a guideline spec file (the ``guidelines:`` section's keys, :mod:`rvmsim.guidelines`).

    Raises
    ------
    SceneError
        A missing or unreadable file, malformed YAML or a bad key (naming this file, the line
        and the key).
    """
    path = Path(path)
    text = read_text(path, SceneError, what="guideline spec file")
    data = parse_yaml_mapping(text, str(path), SceneError, "a guideline spec file")
    try:
        return GuidelineSpec.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, str(path), key_lines(text),
                                          SceneError) from None


def _check_sites(scene: Scene, lines: Mapping[KeyPath, int]) -> None:
    """Every site the scene names loads (:func:`scene_site_entry`:
    a bundled name, or a site file next to the scene, whose own errors name that file and
    its key), and none is named twice."""

    seen: set[str] = set()
    for i, entry in enumerate(scene.sites):
        line = lines.get(("sites", i), lines.get(("sites",)))
        name = scene_site_entry(scene, i, entry, line).name
        if name in seen:
            raise SceneError(scene.source, f"sites.{i}", f"site {name!r} is named twice", line)
        seen.add(name)


#: Focal lengths lie within these factors of the longest image side (a fisheye has about
#: 1/π, a narrow lens a few; outside, the render's cube faces degenerate).
FOCAL_FACTORS = (0.01, 100.0)


def camera_problem(camera: CameraSpec) -> tuple[str, str] | None:
    """(dotted key, one-line message) of a camera whose values the renderer cannot use, or
    None: an image size over the limits (:func:`rvmsim._io.image_size_problem`, at least
    16 px a side), focal lengths outside :data:`FOCAL_FACTORS` of the longest image side, or
    a principal point more than an image width (height) outside the image."""
    w, h = camera.image_size
    problem = image_size_problem(w, h, min_side=16)
    if problem is not None:
        return "camera.image_size", problem
    intr = camera.intrinsics
    fx, fy, cx, cy, _ = intr.resolve(w, h)
    given = ("K" if intr.K is not None else "horizontal_fov_deg"
             if intr.horizontal_fov_deg is not None else "focal_length_mm"
             if intr.focal_length_mm is not None else None)
    side = max(w, h)
    lo, hi = FOCAL_FACTORS[0] * side, FOCAL_FACTORS[1] * side
    for name, f in (("fx", fx), ("fy", fy)):
        if not lo <= f <= hi:
            return (f"camera.intrinsics.{given or name}",
                    f"gives {name} = {f:.6g} px/rad, outside [{lo:g}, {hi:g}] "
                    f"({FOCAL_FACTORS[0]:g} to {FOCAL_FACTORS[1]:g} times the longest image side)")
    for name, c, n in (("cx", cx, w), ("cy", cy, h)):
        if not -n <= c <= 2 * n:
            return (f"camera.intrinsics.{'K' if intr.K is not None else name}",
                    f"{name} = {c:.6g} px is outside [{-n}, {2 * n}] (the principal point lies "
                    "at most an image size outside the image)")
    return None


def mesh_parts(scene: Scene) -> list[tuple[str, MeshPart]]:
    """The scene's mesh-file parts with their dotted keys (``vehicle.bumper.mesh``, ...)."""
    out: list[tuple[str, MeshPart]] = []
    if scene.vehicle is None:
        return out
    for name in ("bumper", "garnish", "trunk"):
        part = getattr(scene.vehicle, name)
        if isinstance(part, MeshPart):
            out.append((f"vehicle.{name}.mesh", part))
    for i, part in enumerate(scene.vehicle.extra):
        out.append((f"vehicle.extra.{i}.mesh", part))
    return out


def absolute_mesh_paths(doc: object, base_dir: str | Path) -> list[Path]:
    """Make every mesh path in a scene *document* (as parsed from YAML) absolute, resolved
    against ``base_dir``, in place, so the document loads from any folder; returns them."""
    out: list[Path] = []
    veh = doc.get("vehicle") if isinstance(doc, dict) else None
    if not isinstance(veh, dict):
        return out
    parts = [veh.get(k) for k in ("bumper", "garnish", "trunk")]
    parts += list(veh.get("extra") or []) if isinstance(veh.get("extra"), list) else []
    for part in parts:
        if isinstance(part, dict) and isinstance(part.get("mesh"), str):
            p = Path(part["mesh"]).expanduser()
            p = p if p.is_absolute() else (Path(base_dir) / p).resolve()
            part["mesh"] = str(p)
            out.append(p)
    return out


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : path
        The YAML scene file.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Unreadable file, malformed YAML, or any invalid key (message names file, line, key).
    """
    return read_scene_document(path)[0]


def read_scene_document(path: str | Path) -> tuple[Scene, dict[str, Any]]:
    """:func:`load_scene`, also returning the parsed YAML document (for tools that derive
    other scenes from it: sweeps, cluster tasks; a mapping, as the scene loaded).  Same
    errors."""
    path = Path(path)
    text = read_text(path, SceneError)
    data = parse_yaml(text, str(path), SceneError)
    return scene_from_dict(data, base_dir=path.parent, source=str(path), text=text), data


def scene_site_entry(scene: Scene, i: int, entry: str, line: int | None = None
                     ) -> SiteDefinition:
    """Entry ``i`` of the scene's ``sites:`` (the scene loader checks every entry with it).

    Raises
    ------
    SiteError
        A missing site file or an unknown name, naming the scene file (``line`` of it) and
        the key ``sites.<i>``; a bad site file names that file and its key.
    """
    if entry not in BUNDLED_SITES:
        if not is_site_file(entry):
            raise SiteError(scene.source, f"sites.{i}", f"unknown site {entry!r} (bundled: "
                            f"{', '.join(BUNDLED_SITES)}; or a site file, .yaml)", line)
        path = scene.resolve_path(entry)
        if not path.is_file():
            raise SiteError(scene.source, f"sites.{i}", f"site file not found: {path}", line)
    return site_definition(entry, scene.base_dir)
