"""Build the scene's meshes with trimesh: one :class:`~rvmsim.scene.Part` per labelled surface.

Every stripe, every F/G lower patch, every guideline and each body part is its own mesh,
so the renderer can give it its own label.  The test site's surfaces are
:mod:`rvmsim.scene.site`; the vehicle's body parts (parametric blocks or mesh files) are
built here.  Geometry is in the scene frame (metres, Y toward the ground).
"""

from __future__ import annotations

import trimesh

from .. import labels as L
from ..errors import SceneError
from .primitives import Part, swept_block
from .schema import BlockPart, MeshPart, Rgb, Scene
from .site import site_parts

__all__ = ["build_parts"]

GARNISH_COLOR = (0.08, 0.08, 0.09)
#: Colour of an extra mesh part without one of its own.
EXTRA_COLOR = (0.2, 0.2, 0.2)


def _load_mesh_part(scene: Scene, key: str, part: MeshPart) -> trimesh.Trimesh:
    """The mesh file of ``part`` (at dotted ``key`` of the scene), moved into the scene frame."""
    path = scene.resolve_path(part.mesh)
    try:
        loaded = trimesh.load(str(path), force="mesh")
    except Exception as err:  # trimesh raises many kinds for bad files
        raise SceneError(scene.source, key, f"cannot load mesh file {path}: {err}") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise SceneError(scene.source, key, f"mesh file {path} holds no triangles")
    mesh = loaded.copy()
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
        mesh = _load_mesh_part(scene, f"vehicle.{name}.mesh", spec)
    color = spec.color if spec.color is not None else default_color
    return [Part(name, label, mesh, color)]


def build_parts(scene: Scene) -> list[Part]:
    """Every labelled surface of ``scene``: ground, test objects, guidelines, board, body.

    Raises
    ------
    SceneError
        When a mesh file cannot be loaded.
    """
    v = scene.vehicle
    parts = site_parts(scene)
    parts += _body_part(scene, "bumper", L.BUMPER, v.paint)
    parts += _body_part(scene, "garnish", L.GARNISH, GARNISH_COLOR)
    parts += _body_part(scene, "trunk", L.TRUNK, v.paint)
    for i, extra in enumerate(v.extra):
        mesh = _load_mesh_part(scene, f"vehicle.extra.{i}.mesh", extra)
        color = extra.color if extra.color is not None else EXTRA_COLOR
        parts.append(Part(f"extra_{i}", L.EXTRA_PART_BASE + i, mesh, color))
    return parts
