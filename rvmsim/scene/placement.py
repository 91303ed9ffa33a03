"""A scene at a test site: the same car and camera with the site's objects placed behind it.

The site data (:mod:`rvmsim.scene.sitedefs`) places its objects by the vehicle's width; this
module measures that width (from the body parts, or their mesh files) and builds the scene at
the site.  It sits above the scene loader and the meshes, which it uses; nothing else in
``rvmsim.scene`` imports it.

Convention
----------
Scene frame of :mod:`rvmsim.camera` (x toward the driver's side, z rearward from the
rear-most point of the bumper, metres).
"""

from __future__ import annotations

from ..errors import RvmsimError
from .board import PatternBoard
from .loading import mesh_parts, scene_site_entry
from .meshes import load_mesh_part
from .schema import BlockPart, MeshPart, Scene, TestSite, Vehicle
from .sitedefs import BUNDLED_SITES, DEFAULT_SITE, SiteDefinition, bundled_site, place_objects

__all__ = ["vehicle_width", "scene_vehicle_width", "site_scene", "scene_site", "scene_sites"]


def vehicle_width(vehicle: object) -> float | None:
    """The vehicle's overall width, metres: ``vehicle.width`` when given, else its widest
    body part; None without a vehicle, or when a part is a mesh (the caller measures the
    meshes, which need loading: :func:`scene_vehicle_width`)."""
    if not isinstance(vehicle, Vehicle):
        return None
    if vehicle.width is not None:
        return float(vehicle.width)
    if any(isinstance(p, MeshPart)
           for p in (vehicle.bumper, vehicle.garnish, vehicle.trunk, *vehicle.extra)):
        return None
    widths = [p.width for p in (vehicle.bumper, vehicle.garnish, vehicle.trunk)
              if isinstance(p, BlockPart)]
    return max(widths) if widths else None


def scene_vehicle_width(scene: Scene) -> float:
    """The width (metres) a site places its objects by (:func:`vehicle_width`; mesh parts
    measured from their files).

    Raises
    ------
    RvmsimError
        A scene without a vehicle and without ``vehicle.width``.
    """
    width = vehicle_width(scene.vehicle)
    if width is not None:
        return width
    if scene.vehicle is None:
        raise RvmsimError(f"{scene.source}: vehicle: a site placed by the vehicle's width "
                          "needs a vehicle (or vehicle.width)")
    v = scene.vehicle
    widths = [p.width for p in (v.bumper, v.garnish, v.trunk) if isinstance(p, BlockPart)]
    for key, part in mesh_parts(scene):  # the widest part, block or mesh
        x = load_mesh_part(scene, key, part).bounds[:, 0]
        widths.append(float(x[1] - x[0]))
    if not widths:
        raise RvmsimError(f"{scene.source}: vehicle: a site placed by the vehicle's width "
                          "needs a body part (or vehicle.width)")
    return max(widths)


def site_scene(scene: Scene, site: str | SiteDefinition) -> Scene:
    """``scene`` at ``site``: the same car and camera, with the site's objects placed behind
    it and nothing else of the FMVSS test site (no objects A–G, guidelines, board or ground
    patterns); ``scene`` itself at its FMVSS site (``kind: fmvss111``).

    Raises
    ------
    RvmsimError
        An unknown site, a bad site file, or a scene already at another site asked for the
        FMVSS site.
    """
    definition = site if isinstance(site, SiteDefinition) else scene_site(scene, site)
    current = scene.test_site.site
    if definition.kind == "fmvss111":
        if current != DEFAULT_SITE:
            raise RvmsimError(f"{scene.source}: this scene is at site {current!r}; load the "
                              "scene file again for its FMVSS site")
        return scene
    if current == definition.name:
        return scene
    if current != DEFAULT_SITE:
        raise RvmsimError(f"{scene.source}: this scene is at site {current!r} already")
    objects = place_objects(definition, scene_vehicle_width(scene))
    ts = scene.test_site
    site_ts = TestSite(fmvss=False, board=PatternBoard(enabled=False),
                       ground_size=ts.ground_size, ground_color=ts.ground_color,
                       site=definition.name, site_objects=objects)
    return scene.model_copy(update={"test_site": site_ts})


def scene_site(scene: Scene, name: str) -> SiteDefinition:
    """The site ``name`` as ``scene`` defines it: a site file the scene names under
    ``sites:`` whose ``name`` is ``name``, else the bundled site of that name.

    Raises
    ------
    RvmsimError
        An unknown site, or a bad site file (one line naming the file and key).
    """
    for i, entry in enumerate(scene.sites):
        if entry in BUNDLED_SITES:
            continue
        site = scene_site_entry(scene, i, entry)
        if site.name == name:
            return site
    return bundled_site(name)


def scene_sites(scene: Scene) -> list[SiteDefinition]:
    """Every site ``scene`` names (``sites:``), in order."""
    return [scene_site_entry(scene, i, entry) for i, entry in enumerate(scene.sites)]
