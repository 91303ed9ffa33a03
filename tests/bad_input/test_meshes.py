"""Bad mesh files named by a scene (issue #14, group 1): unreadable, corrupt, empty, over
the vertex limit, non-finite or absurd coordinates, in each format (STL, OBJ, PLY, glTF,
GLB); the error names the scene file, the key and the mesh file."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest
import trimesh

from .conftest import SMALL_SCENE, small_scene
from .harness import MEMORY, Case, check_case

RENDER = ("render", SMALL_SCENE, "--out", "r", "--no-progress")
BUMPER = "vehicle.bumper.mesh"


def _binary_stl(triangles: np.ndarray, count: int | None = None) -> bytes:
    """A binary STL of (n, 3, 3) float32 triangles (``count``: the header's triangle count)."""
    tri = np.asarray(triangles, dtype=np.float32).reshape(-1, 9)
    body = b"".join(struct.pack("<3f", 0, 0, 0) + t.tobytes() + b"\0\0" for t in tri)
    return b"\0" * 80 + struct.pack("<I", len(tri) if count is None else count) + body


def _box(scale: float = 1.0) -> trimesh.Trimesh:
    box = trimesh.creation.box((0.4, 0.2, 0.1))
    box.vertices *= scale
    return box


def _export(name: str, mesh: trimesh.Trimesh) -> bytes:
    data = mesh.export(file_type=name.rsplit(".", 1)[1])
    return data.encode() if isinstance(data, str) else data


def _mesh_scene(name: str, data: bytes | None, key: str = "vehicle.bumper", **part):
    """Setup: ``name`` holds ``data`` (None: a directory) and the scene's part at ``key``
    is that mesh file."""
    def setup(folder):
        if data is None:
            (folder / name).mkdir()
        else:
            (folder / name).write_bytes(data)
        if key.startswith("vehicle.extra"):
            small_scene(folder, {"vehicle.extra": [{"mesh": name, **part}]})
        else:
            small_scene(folder, {key: {"mesh": name, **part}})
    return setup


STL_TRIANGLE = np.array([[[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]]])
ASCII_NAN_STL = (b"solid x\nfacet normal 0 0 1\nouter loop\nvertex nan 0 0\nvertex 1 0 0\n"
                 b"vertex 0 1 0\nendloop\nendfacet\nendsolid x\n")
OBJ_NAN = b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
OBJ_INF = b"v inf 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
OBJ_FAR = b"v 1e30 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
PLY_HEADER = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 1\n"
              b"property list uchar int vertex_indices\nend_header\n")
PLY_INF = PLY_HEADER + struct.pack("<9f", math.inf, 0, 0, 1, 0, 0, 0, 1, 0) + \
    struct.pack("<B3i", 3, 0, 1, 2)

#: (case id, file name, contents (None: a directory), what the message says)
FILES = [
    ("stl-empty", "b.stl", b"", "empty"),
    ("stl-junk", "b.stl", b"this is not a mesh at all\n" * 4, "b.stl"),
    ("stl-header-lies", "b.stl", _binary_stl(STL_TRIANGLE, count=10**9), "b.stl"),
    ("stl-1e38", "b.stl", _binary_stl(STL_TRIANGLE * 1e38), "coordinates"),
    ("stl-nan", "b.stl", ASCII_NAN_STL, "b.stl"),
    ("stl-no-triangles", "b.stl", b"solid x\nendsolid x\n", "b.stl"),
    ("stl-directory", "b.stl", None, "b.stl"),
    ("obj-empty", "b.obj", b"", "empty"),
    ("obj-junk", "b.obj", b"\x00\xff\x10garbage" * 50, "b.obj"),
    ("obj-nan", "b.obj", OBJ_NAN, "b.obj"),
    ("obj-inf", "b.obj", OBJ_INF, "b.obj"),
    ("obj-1e30", "b.obj", OBJ_FAR, "coordinates"),
    ("obj-vertices-only", "b.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no triangles"),
    ("obj-bad-index", "b.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n", "b.obj"),
    ("ply-empty", "b.ply", b"", "empty"),
    ("ply-junk", "b.ply", b"ply\nformat nonsense\n", "b.ply"),
    ("ply-truncated", "b.ply", PLY_HEADER + b"\0" * 7, "b.ply"),
    ("ply-inf", "b.ply", PLY_INF, "b.ply"),
    ("gltf-junk", "b.gltf", b"{not json", "b.gltf"),
    ("gltf-missing-buffer", "b.gltf",
     b'{"asset": {"version": "2.0"}, "buffers": [{"uri": "gone.bin", "byteLength": 36}]}',
     "b.gltf"),
    ("glb-junk", "b.glb", b"glTF\x02\0\0\0" + b"\0" * 20, "b.glb"),
    ("glb-far", "b.glb", _export("b.glb", _box(1e9)), "coordinates"),
    ("glb-empty", "b.glb", b"", "empty"),
]

#: Cases run in a child of their own: a header counting 10⁹ triangles (50 GB if believed).
ISOLATED = {"stl-header-lies": MEMORY}
CASES = [Case(f"mesh-{i}", RENDER, (SMALL_SCENE, BUMPER, msg), _mesh_scene(name, data), isolate=ISOLATED.get(i, "")) for i, name, data, msg in FILES]
CASES += [
    Case("mesh-missing", RENDER, (SMALL_SCENE, BUMPER, "gone.stl"),
         lambda f: small_scene(f, {"vehicle.bumper": {"mesh": "gone.stl"}})),
    Case("mesh-units-mm-far", RENDER, (SMALL_SCENE, BUMPER, "coordinates"),
         _mesh_scene("b.stl", _export("b.stl", _box(1e7)), units="mm")),
    Case("mesh-translation-nan", RENDER, (SMALL_SCENE, "vehicle.bumper.translation.1"),
         _mesh_scene("b.stl", _export("b.stl", _box()), translation=[0, math.nan, 0])),
    Case("mesh-vertex-limit", RENDER, (SMALL_SCENE, BUMPER, "RVMSIM_MAX_MESH_VERTICES"),
         _mesh_scene("b.obj", _export("b.obj", _box())),
         env={"RVMSIM_MAX_MESH_VERTICES": "6"}),
    Case("mesh-size-limit", RENDER, (SMALL_SCENE, BUMPER, "RVMSIM_MAX_MESH_VERTICES"),
         _mesh_scene("b.stl", _export("b.stl", _box())),
         env={"RVMSIM_MAX_MESH_VERTICES": "1"}),
    Case("mesh-extra-junk", RENDER, (SMALL_SCENE, "vehicle.extra.0.mesh", "e.ply"),
         _mesh_scene("e.ply", b"ply\n", key="vehicle.extra")),
    Case("mesh-garnish-empty", RENDER, (SMALL_SCENE, "vehicle.garnish.mesh", "g.obj"),
         _mesh_scene("g.obj", b"", key="vehicle.garnish")),
    Case("mesh-process-1e38", ("process", SMALL_SCENE, "--out", "p", "--no-progress"),
         (SMALL_SCENE, BUMPER, "b.stl"), _mesh_scene("b.stl", _binary_stl(STL_TRIANGLE * 1e38))),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_mesh_file(case, case_dir):
    check_case(case, case_dir)
