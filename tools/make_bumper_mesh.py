"""Generate assets/bumper_rounded.stl: a rear bumper with rounded edges, in millimetres.

The bundled vehicle F uses it to exercise mesh-file body parts (STL through trimesh, with
units and a transform).  Coordinates are the scene frame in mm: X toward the driver's side,
Y down, Z rearward, origin on the ground below the rearmost point of the bumper.

    python tools/make_bumper_mesh.py            # rewrites assets/bumper_rounded.stl
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import trimesh


def bumper(width=1860.0, bottom=420.0, top=800.0, depth=380.0, sweep=100.0, fillet=90.0,
           n_along=64, n_arc=10) -> trimesh.Trimesh:
    # Cross-section in (height h, rearward offset r) around the rear face, rounded at both
    # rear edges, closed by the (hidden) front face.
    prof = []
    for a in np.linspace(math.pi / 2, 0, n_arc):  # lower rear edge
        prof.append((bottom + fillet - fillet * math.sin(a), -fillet + fillet * math.cos(a)))
    for a in np.linspace(0, math.pi / 2, n_arc):  # upper rear edge
        prof.append((top - fillet + fillet * math.sin(a), -fillet + fillet * math.cos(a)))
    prof.append((top, -depth))
    prof.append((bottom, -depth))
    prof = np.asarray(prof)
    m = len(prof)
    xs = np.linspace(-width / 2, width / 2, n_along)
    verts = []
    for x in xs:
        z0 = -sweep * (2 * x / width) ** 2  # plan-view sweep of the rear face
        for h, r in prof:
            verts.append((x, -h, z0 + r))
    verts = np.asarray(verts)
    faces = []
    for i in range(n_along - 1):
        for j in range(m):
            a, b = i * m + j, i * m + (j + 1) % m
            c, d = a + m, b + m
            faces += [[a, b, c], [c, b, d]]
    cap0 = list(range(m))
    cap1 = [(n_along - 1) * m + j for j in range(m)]
    for k in range(1, m - 1):
        faces.append([cap0[0], cap0[k + 1], cap0[k]])
        faces.append([cap1[0], cap1[k], cap1[k + 1]])
    mesh = trimesh.Trimesh(verts, np.asarray(faces), process=True)
    trimesh.repair.fix_normals(mesh)
    return mesh


if __name__ == "__main__":
    out = Path(__file__).resolve().parent.parent / "assets" / "bumper_rounded.stl"
    mesh = bumper()
    mesh.export(out)
    print(f"wrote {out}: {len(mesh.faces)} triangles, watertight={mesh.is_watertight}, "
          f"bounds (mm) {mesh.bounds.round(1).tolist()}")
