"""Mesh primitives (trimesh) and :class:`Part`, one labelled surface of the scene.

Geometry is in the scene frame (metres, Y toward the ground): a height ``h`` above the ground
is ``y = -h``.  Azimuth on a vertical cylinder (degrees): 0 faces +Z, 90 faces +X.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import numpy as np
import trimesh

from .schema import BlockPart, Rgb


__all__ = ["Part", "cylinder_side", "disk", "quad", "ground_rect", "ground_strip", "swept_block",
           "concatenate", "CIRCLE_SECTIONS"]

#: Segments of a full circle (cylinders, disks).
CIRCLE_SECTIONS = 128

@dataclass(frozen=True)
class Part:
    """One labelled surface of the scene.

    Attributes
    ----------
    name : str
        Readable name (``stripe_F``).
    label : int
        Label ID from :mod:`rvmsim.labels`.
    mesh : trimesh.Trimesh
        Geometry in the scene frame, metres.
    color : (3,) float
        Base colour, linear 0–1.
    texture : str or None
        Name of a procedural texture (``"asphalt"``) modulating the colour; the mesh then
        carries UV coordinates.
    smooth : bool
        Shade with interpolated vertex normals (curved surfaces) instead of face normals.
    """

    name: str
    label: int
    mesh: trimesh.Trimesh
    color: Rgb
    texture: str | None = None
    smooth: bool = False


# ---------------------------------------------------------------------------- primitives
def cylinder_side(
    radius: float,
    h0: float,
    h1: float,
    az0_deg: float,
    az1_deg: float,
    centre_xz: tuple[float, float],
) -> trimesh.Trimesh:
    """Part of a vertical cylinder's side between heights ``h0`` < ``h1`` (metres above the
    ground) and azimuths ``az0_deg`` < ``az1_deg``; faces point outward."""

    span = math.radians(az1_deg - az0_deg)
    n = max(2, int(math.ceil(span / (2 * math.pi / CIRCLE_SECTIONS))) + 1)
    az = np.linspace(math.radians(az0_deg), math.radians(az1_deg), n)
    x = centre_xz[0] + radius * np.sin(az)
    z = centre_xz[1] + radius * np.cos(az)
    bottom = np.stack([x, np.full(n, -h0), z], axis=1)
    top = np.stack([x, np.full(n, -h1), z], axis=1)
    verts = np.concatenate([bottom, top])
    i = np.arange(n - 1)
    # With Y down and azimuth increasing from +Z toward +X, (b_i, t_i, b_i+1) winds outward.
    faces = np.concatenate(
        [np.stack([i, i + n, i + 1], axis=1), np.stack([i + 1, i + n, i + n + 1], axis=1)]
    )
    return trimesh.Trimesh(verts, faces, process=False)


def disk(radius: float, height: float, centre_xz: tuple[float, float]) -> trimesh.Trimesh:
    """Horizontal disk at ``height`` metres above ground, facing up (−Y)."""

    n = CIRCLE_SECTIONS
    az = np.linspace(0, 2 * math.pi, n, endpoint=False)
    ring = np.stack(
        [centre_xz[0] + radius * np.sin(az), np.full(n, -height), centre_xz[1] + radius * np.cos(az)],
        axis=1,
    )
    verts = np.concatenate([[[centre_xz[0], -height, centre_xz[1]]], ring])
    i = np.arange(n)
    faces = np.stack([np.zeros(n, int), 1 + (i + 1) % n, 1 + i], axis=1)
    return trimesh.Trimesh(verts, faces, process=False)


def quad(corners: np.ndarray) -> trimesh.Trimesh:
    """A planar quadrilateral from 4 corners (in order around it)."""

    c = np.asarray(corners, dtype=np.float64).reshape(4, 3)
    return trimesh.Trimesh(c, [[0, 1, 2], [0, 2, 3]], process=False)


def swept_block(part: BlockPart, *, sections: int = 48) -> trimesh.Trimesh:
    """Closed mesh of a parametric body part (see :class:`~rvmsim.scene.BlockPart`)."""

    x = np.linspace(-part.width / 2, part.width / 2, sections)
    z_rear = -part.setback - part.sweep * (2 * x / part.width) ** 2
    lean = (part.top - part.bottom) * math.tan(math.radians(part.lean_deg))
    profile = [
        (np.full_like(x, -part.bottom), z_rear),
        (np.full_like(x, -part.top), z_rear - lean),
        (np.full_like(x, -part.top), z_rear - lean - part.depth),
        (np.full_like(x, -part.bottom), z_rear - part.depth),
    ]
    verts = np.concatenate([np.stack([x, y, z], axis=1) for y, z in profile])  # 4 rings of n
    n = sections
    faces = []
    for a in range(4):
        b = (a + 1) % 4
        for i in range(n - 1):
            p, q = a * n + i, b * n + i
            faces += [[p, p + 1, q], [q, p + 1, q + 1]]
    faces += [[0, n, 2 * n], [0, 2 * n, 3 * n]]  # end caps
    e = n - 1
    faces += [[e, 2 * n + e, n + e], [e, 3 * n + e, 2 * n + e]]
    mesh = trimesh.Trimesh(verts, np.asarray(faces), process=True)
    trimesh.repair.fix_normals(mesh)
    return mesh


def ground_rect(x0: float, x1: float, z0: float, z1: float, lift: float) -> trimesh.Trimesh:
    """Rectangle [x0, x1] × [z0, z1] (metres) lying ``lift`` metres above the ground."""
    y = -lift
    return quad(np.array([[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]]))


def ground_strip(points_xz: np.ndarray, width: float, lift: float) -> trimesh.Trimesh:
    """A flat strip ``width`` metres wide centred on the polyline ``points_xz`` ((N, 2) x, z
    metres), ``lift`` metres above the ground, facing up.

    Convention
    ----------
    Each vertex pair lies on the bisector of its two segments' normals, scaled so that both
    segments keep the full width (a mitred joint); consecutive duplicate points are dropped.
    """
    pts = np.asarray(points_xz, np.float64).reshape(-1, 2)
    keep = np.r_[True, np.any(np.diff(pts, axis=0) != 0, axis=1)]
    pts = pts[keep]
    if len(pts) < 2:
        raise ValueError("a strip needs two distinct points")
    d = np.diff(pts, axis=0)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    n = np.stack([-d[:, 1], d[:, 0]], axis=1)  # segment normals
    nv = np.vstack([n[:1], n[:-1] + n[1:], n[-1:]])
    nv /= np.linalg.norm(nv, axis=1, keepdims=True)
    seg_n = np.vstack([n[:1], n])  # a segment's normal at each vertex (for the mitre length)
    scale = (width / 2.0) / np.maximum(np.sum(nv * seg_n, axis=1), 0.2)
    left, right = pts + nv * scale[:, None], pts - nv * scale[:, None]
    y = -lift
    verts = np.empty((2 * len(pts), 3))
    verts[0::2] = np.column_stack([left[:, 0], np.full(len(pts), y), left[:, 1]])
    verts[1::2] = np.column_stack([right[:, 0], np.full(len(pts), y), right[:, 1]])
    i = 2 * np.arange(len(pts) - 1)
    # wound as ground_rect's quads, normals up (−Y): `left` lies to the left of the walk
    faces = np.concatenate([np.stack([i, i + 1, i + 2], 1), np.stack([i + 1, i + 3, i + 2], 1)])
    return trimesh.Trimesh(verts, faces, process=False)


def concatenate(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """The meshes as one mesh (``trimesh.util.concatenate``, typed)."""

    return cast(trimesh.Trimesh, trimesh.util.concatenate(meshes))
