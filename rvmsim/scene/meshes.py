"""Build the scene's meshes with trimesh: one :class:`~rvmsim.scene.Part` per labelled surface.

Every stripe, every F/G lower patch, every guideline and each body part is its own mesh,
so the renderer can give it its own label.  The test site's surfaces are
:mod:`rvmsim.scene.site`; the vehicle's body parts (parametric blocks or mesh files) are
built here.  Geometry is in the scene frame (metres, Y toward the ground).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from .. import labels as L
from .._io import env_limit
from ..errors import SceneError
from .fields import MAX_METRES
from .primitives import Part, swept_block
from .schema import BlockPart, MeshPart, Rgb, Scene
from .site import site_parts


__all__ = ["build_parts", "load_mesh_part", "DEFAULT_MAX_MESH_VERTICES", "MESH_BYTES_PER_VERTEX",
           "max_mesh_vertices"]

#: Most vertices of one mesh file unless ``RVMSIM_MAX_MESH_VERTICES`` says otherwise.
DEFAULT_MAX_MESH_VERTICES = 5_000_000
#: A mesh file may be at most this many bytes per allowed vertex long (an ASCII STL takes
#: about 85, a binary STL 17): a larger file is refused before it is read.
MESH_BYTES_PER_VERTEX = 200


def max_mesh_vertices() -> int:
    """Most vertices of one mesh file: ``RVMSIM_MAX_MESH_VERTICES`` or
    :data:`DEFAULT_MAX_MESH_VERTICES`."""
    return env_limit("RVMSIM_MAX_MESH_VERTICES", DEFAULT_MAX_MESH_VERTICES)


def _read_mesh_file(path: Path) -> trimesh.Trimesh:
    """The mesh file at ``path`` as one unprocessed Trimesh, or the reason it is unusable
    (raised as ValueError, one line)."""

    limit = max_mesh_vertices()
    try:
        size = path.stat().st_size
    except OSError as err:
        raise ValueError(f"cannot read mesh file {path} ({err.strerror or err})") from None
    if size == 0:
        raise ValueError(f"mesh file {path} is empty")
    if size > limit * MESH_BYTES_PER_VERTEX:
        raise ValueError(f"mesh file {path} is {size} bytes, over {limit * MESH_BYTES_PER_VERTEX}"
                         f" ({MESH_BYTES_PER_VERTEX} per vertex of the limit of {limit} vertices; "
                         "raise it with the environment variable RVMSIM_MAX_MESH_VERTICES)")
    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as err:  # noqa: BLE001 - trimesh raises many kinds for bad files
        first = (str(err).strip().splitlines() or [""])[0][:200]
        raise ValueError(f"cannot load mesh file {path}: {type(err).__name__}"
                         + (f": {first}" if first else "")) from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"mesh file {path} holds no triangles")
    if len(loaded.vertices) > limit:
        raise ValueError(f"mesh file {path} has {len(loaded.vertices)} vertices, over the limit "
                         f"of {limit} (raise it with the environment variable "
                         "RVMSIM_MAX_MESH_VERTICES)")
    if not np.isfinite(loaded.vertices).all():
        raise ValueError(f"mesh file {path} has non-finite vertex coordinates")
    return loaded

GARNISH_COLOR = (0.08, 0.08, 0.09)
#: Colour of an extra mesh part without one of its own.
EXTRA_COLOR = (0.2, 0.2, 0.2)


def load_mesh_part(scene: Scene, key: str, part: MeshPart) -> trimesh.Trimesh:
    """The mesh file of ``part`` (at dotted ``key`` of the scene), moved into the scene frame."""
    path = scene.resolve_path(part.mesh)
    try:
        mesh = _read_mesh_file(path)
    except ValueError as err:
        raise SceneError(scene.source, key, str(err)) from None
    reach = float(np.abs(mesh.vertices).max()) * part.scale
    if reach > MAX_METRES:
        raise SceneError(scene.source, key, f"mesh file {path} has coordinates up to "
                         f"{reach:.3g} m (units: {part.units}; a scene reaches at most "
                         f"{MAX_METRES:g} m): are its units right?")
    mesh.process()  # merge duplicate vertices etc., as trimesh.load does by default
    mesh.apply_transform(part.transform())
    return mesh


def _body_part(scene: Scene, name: str, label: int, default_color: Rgb) -> list[Part]:
    """The vehicle part ``name`` (``bumper``, ``garnish``, ``trunk``) as a Part, if given."""
    spec = getattr(scene.vehicle, name)
    if spec is None:
        return []
    if isinstance(spec, BlockPart):
        mesh = swept_block(spec)
    else:
        mesh = load_mesh_part(scene, f"vehicle.{name}.mesh", spec)
    color = spec.color if spec.color is not None else default_color
    return [Part(name, label, mesh, color)]


def build_parts(scene: Scene) -> list[Part]:
    """Every labelled surface of ``scene``: ground, test objects, guidelines, board, body
    (moved with the scene's ``load_state``, when it has one).

    Raises
    ------
    SceneError
        When a mesh file cannot be loaded.
    """
    v = scene.vehicle
    site = site_parts(scene)
    if v is None:
        return site
    parts = list(site)
    parts += _body_part(scene, "bumper", L.BUMPER, v.paint)
    parts += _body_part(scene, "garnish", L.GARNISH, GARNISH_COLOR)
    parts += _body_part(scene, "trunk", L.TRUNK, v.paint)
    for i, extra in enumerate(v.extra):
        mesh = load_mesh_part(scene, f"vehicle.extra.{i}.mesh", extra)
        color = extra.color if extra.color is not None else EXTRA_COLOR
        parts.append(Part(f"extra_{i}", L.EXTRA_PART_BASE + i, mesh, color))
    motion = scene.body_motion()
    if motion is not None:  # the body under the scene's load: every vehicle part moves
        for p in parts[len(site):]:
            p.mesh.apply_transform(motion)
    return parts
