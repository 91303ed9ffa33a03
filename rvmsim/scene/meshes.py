"""Build the scene's meshes with trimesh: one :class:`Part` per labelled surface.

Every stripe, every F/G lower patch, every guideline and each body part is its own mesh,
so the renderer can give it its own label.  Geometry is in the scene frame (metres,
Y toward the ground): a height ``h`` above the ground is ``y = -h``.

Azimuth on a test object (degrees): 0 faces +Z (away from the car), 90 faces +X (the
driver's side), 180 faces the car.

:func:`site_landmarks` lists known 3D points of the built geometry with the label they lie
on, for tests and for validation against real captures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from .. import labels as L
from ..camera import rotation_from_ypr
from ..errors import SceneError
from .schema import BlockPart, GroundPattern, MeshPart, PatternBoard, Scene

__all__ = [
    "Part",
    "Landmark",
    "CheckerCorner",
    "build_parts",
    "site_landmarks",
    "checker_corners",
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

#: Painted guidelines float this far above the ground (avoids depth fighting), metres.
GUIDELINE_LIFT_M = 0.003
#: A board lying on the ground: plate thickness; its black squares float a further lift.
BOARD_LIFT_M = 0.006
_SQUARE_LIFT_M = 0.003
#: Ground patterns: the checker lies this far above the ground; white rectangles and black
#: discs lie on top of it, each a further lift up (no depth fighting at 10 m).
PATTERN_LIFT_M = 0.004
_PATTERN_LAYER_M = 0.003
_CIRCLE_SECTIONS = 128

BLACK = (0.03, 0.03, 0.03)
WHITE = (0.92, 0.92, 0.92)
OBJECT_COLOR = (0.93, 0.93, 0.90)
GARNISH_COLOR = (0.08, 0.08, 0.09)


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
    color: tuple[float, float, float]
    texture: str | None = None
    smooth: bool = False


@dataclass(frozen=True)
class Landmark:
    """A known 3D point of the built scene.

    ``kind`` is ``"interior"`` (well inside the surface labelled ``label``), ``"edge"`` (on a
    straight border between ``label`` and something else) or ``"corner"`` (a corner of the
    surface: the label fills only a wedge around it).  ``normal`` is the unit normal of
    that surface at the point (scene frame), so users can tell grazing views apart.
    """

    name: str
    point: tuple[float, float, float]
    label: int
    kind: str
    normal: tuple[float, float, float] = (0.0, -1.0, 0.0)


@dataclass(frozen=True)
class CheckerCorner:
    """An inner corner of a checker (four squares meet, two black on one diagonal).

    Attributes
    ----------
    name : str
        ``board_inner_i_j`` or ``pattern<k>_i_j``.
    point : (3,) float
        Scene point, metres.
    axis_a, axis_b : (3,) float
        Unit vectors along the checker's two square edges, scene frame: the square
        ``point + [0, s]·axis_a + [0, s]·axis_b`` is black when ``black_ab`` is True.
    square_size : float
        Side of a square, metres.
    label : int
        Label of the surface (board or ground pattern).
    black_ab : bool
        Colour of the square in the ``+a, +b`` quadrant.
    """

    name: str
    point: tuple[float, float, float]
    axis_a: tuple[float, float, float]
    axis_b: tuple[float, float, float]
    square_size: float
    label: int
    black_ab: bool

    @property
    def normal(self) -> tuple[float, float, float]:
        """Unit normal of the checker toward the viewer: ``axis_a × axis_b``."""
        return tuple(float(x) for x in np.cross(self.axis_a, self.axis_b))


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
    n = max(2, int(math.ceil(span / (2 * math.pi / _CIRCLE_SECTIONS))) + 1)
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
    n = _CIRCLE_SECTIONS
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


def _load_mesh_part(scene: Scene, key: str, part: MeshPart) -> trimesh.Trimesh:
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


def _body_part(scene: Scene, name: str, label: int, default_color: tuple) -> list[Part]:
    spec = getattr(scene.vehicle, name)
    if spec is None:
        return []
    if isinstance(spec, BlockPart):
        mesh = swept_block(spec)
    else:
        mesh = _load_mesh_part(scene, f"vehicle.{name}.mesh", spec)
    color = spec.color if spec.color is not None else default_color
    return [Part(name, label, mesh, tuple(color))]


# ---------------------------------------------------------------------------- test site
def stripe_azimuth_deg(scene: Scene, letter: str, centre_xz: tuple[float, float]) -> float:
    """Azimuth (degrees) the F/G vertical stripe is centred on."""
    facing = scene.test_site.vertical_stripe_facing
    if isinstance(facing, (int, float)):
        return float(facing)
    if facing == "vehicle":
        return 180.0
    if facing == "camera":
        cam = scene.camera.mount.position
        dx, dz = cam[0] - centre_xz[0], cam[2] - centre_xz[1]
    else:  # vehicle_centreline
        dx, dz = -centre_xz[0], 0.0
        if abs(dx) < 1e-9:
            return 180.0
    return math.degrees(math.atan2(dx, dz))


def _test_objects(scene: Scene) -> list[Part]:
    site = scene.test_site
    r = site.object_diameter / 2
    height = site.object_height
    parts: list[Part] = []
    for letter in L.OBJECT_LETTERS:
        c = site.object_centre(letter)
        if c is None:
            continue
        top = disk(r, height, c)
        if letter in "ABCDE":
            band0 = height - site.stripe_width
            body = trimesh.util.concatenate([cylinder_side(r, 0.0, band0, 0, 360, c), top])
            stripe = cylinder_side(r, band0, height, 0, 360, c)
            parts += [
                Part(f"object_{letter}", L.object_body(letter), body, OBJECT_COLOR, smooth=True),
                Part(f"stripe_{letter}", L.object_stripe(letter), stripe, BLACK, smooth=True),
            ]
        else:
            az = stripe_azimuth_deg(scene, letter, c)
            half = math.degrees(site.stripe_width / r) / 2
            rest = cylinder_side(r, 0.0, height, az + half, az + 360 - half, c)
            body = trimesh.util.concatenate([rest, top])
            patch_h = site.lower_patch_height
            parts += [
                Part(f"object_{letter}", L.object_body(letter), body, OBJECT_COLOR, smooth=True),
                Part(
                    f"stripe_{letter}",
                    L.object_stripe(letter),
                    cylinder_side(r, patch_h, height, az - half, az + half, c),
                    BLACK,
                    smooth=True,
                ),
                Part(
                    f"stripe_{letter}_lower_patch",
                    L.object_patch(letter),
                    cylinder_side(r, 0.0, patch_h, az - half, az + half, c),
                    BLACK,
                    smooth=True,
                ),
            ]
    return parts


def _ground_rect(x0: float, x1: float, z0: float, z1: float, lift: float) -> trimesh.Trimesh:
    y = -lift
    return quad(np.array([[x0, y, z0], [x1, y, z0], [x1, y, z1], [x0, y, z1]]))


def _guidelines(scene: Scene) -> list[Part]:
    g = scene.test_site.guidelines
    if not g.enabled:
        return []
    hw = g.line_width / 2
    parts = []
    for x, label, name in (
        (g.side_x[0], L.GUIDE_SIDE_NEG_X, "guide_side_neg_x"),
        (g.side_x[1], L.GUIDE_SIDE_POS_X, "guide_side_pos_x"),
    ):
        mesh = _ground_rect(x - hw, x + hw, g.side_z[0], g.side_z[1], GUIDELINE_LIFT_M)
        parts.append(Part(name, label, mesh, tuple(g.color)))
    for n, z in enumerate(g.cross_z, start=1):
        # Cross lines run between the inner edges of the side lines: no overlap, no z-fight.
        mesh = _ground_rect(g.side_x[0] + hw, g.side_x[1] - hw, z - hw, z + hw, GUIDELINE_LIFT_M)
        parts.append(Part(f"guide_cross_{n}", L.guide_cross(n), mesh, tuple(g.color)))
    return parts


def board_frame(board: PatternBoard) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(centre, a, b, normal) of the board's front surface: a along its width (columns),
    b along its height (rows), normal toward the viewer, unit vectors in the scene frame."""
    r = rotation_from_ypr(board.yaw_deg, 0.0, 0.0)
    c = np.asarray(board.position, dtype=np.float64)
    if board.placement == "ground":
        a, b, nrm = r @ [1.0, 0, 0], r @ [0, 0, 1.0], np.array([0, -1.0, 0])
        c = c + nrm * BOARD_LIFT_M
    else:
        a, b, nrm = r @ [1.0, 0, 0], np.array([0, -1.0, 0]), r @ [0, 0, -1.0]
    return c, a, b, nrm


def board_point(board: PatternBoard, sa: float, sb: float, lift: float = 0.0) -> np.ndarray:
    """Scene point at board coordinates (sa, sb) metres from the board centre."""
    c, a, b, nrm = board_frame(board)
    return c + sa * a + sb * b + lift * nrm


def _board(scene: Scene) -> list[Part]:
    board = scene.test_site.board
    if not board.enabled:
        return []
    w, h = board.size
    plate = quad(
        np.array([board_point(board, sa, sb) for sa, sb in
                  [(-w / 2, -h / 2), (w / 2, -h / 2), (w / 2, h / 2), (-w / 2, h / 2)]])
    )
    s = board.square_size
    a0, b0 = -w / 2 + board.margin, -h / 2 + board.margin
    squares = []
    for i in range(board.squares[0]):
        for j in range(board.squares[1]):
            if (i + j) % 2:
                continue
            corners = [
                (a0 + i * s, b0 + j * s),
                (a0 + (i + 1) * s, b0 + j * s),
                (a0 + (i + 1) * s, b0 + (j + 1) * s),
                (a0 + i * s, b0 + (j + 1) * s),
            ]
            squares.append(
                quad(np.array([board_point(board, sa, sb, _SQUARE_LIFT_M) for sa, sb in corners]))
            )
    return [
        Part("pattern_board", L.BOARD, plate, WHITE),
        Part("pattern_board_squares", L.BOARD, trimesh.util.concatenate(squares), BLACK),
    ]


def pattern_point(pattern: GroundPattern, u: float, v: float, lift: float = 0.0) -> np.ndarray:
    """Scene point (metres) at pattern coordinates (u, v), ``lift`` above the ground."""
    a = math.radians(pattern.yaw_deg)
    x = pattern.origin[0] + u * math.cos(a) + v * math.sin(a)
    z = pattern.origin[1] - u * math.sin(a) + v * math.cos(a)
    return np.array([x, -lift, z])


def pattern_axes(pattern: GroundPattern) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors of the pattern's u and v axes in the scene frame."""
    o = pattern_point(pattern, 0.0, 0.0)
    return pattern_point(pattern, 1.0, 0.0) - o, pattern_point(pattern, 0.0, 1.0) - o


def _pattern_cells(pattern: GroundPattern) -> dict[tuple[int, int], tuple[float, float, float, float]]:
    """Checker squares (i, j) → their [u0, v0, u1, v1] after clipping to the checker
    rectangles (a square covered by two rectangles is the union's bounding box)."""
    s = pattern.square_size
    cells: dict[tuple[int, int], tuple[float, float, float, float]] = {}
    for u0, v0, u1, v1 in pattern.checker:
        for i in range(math.floor(u0 / s + 1e-9), math.ceil(u1 / s - 1e-9)):
            for j in range(math.floor(v0 / s + 1e-9), math.ceil(v1 / s - 1e-9)):
                box = (max(u0, i * s), max(v0, j * s), min(u1, (i + 1) * s), min(v1, (j + 1) * s))
                old = cells.get((i, j))
                if old is not None:
                    box = (min(old[0], box[0]), min(old[1], box[1]),
                           max(old[2], box[2]), max(old[3], box[3]))
                cells[(i, j)] = box
    return cells


def _pattern_quads(pattern: GroundPattern, boxes: list, lift: float) -> trimesh.Trimesh:
    quads = [
        quad(np.array([pattern_point(pattern, u, v, lift)
                       for u, v in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))]))
        for u0, v0, u1, v1 in boxes
    ]
    return trimesh.util.concatenate(quads)


def _ground_patterns(scene: Scene) -> list[Part]:
    parts: list[Part] = []
    for k, pattern in enumerate(scene.test_site.ground_patterns):
        cells = _pattern_cells(pattern)
        black = [b for (i, j), b in cells.items() if (i + j) % 2 == 0]
        white = [b for (i, j), b in cells.items() if (i + j) % 2 == 1]
        lift = PATTERN_LIFT_M
        for colour, boxes, tag in ((pattern.black_color, black, "black"),
                                   (pattern.white_color, white, "white")):
            if boxes:
                parts.append(Part(f"pattern{k}_{tag}", L.GROUND_PATTERN,
                                  _pattern_quads(pattern, boxes, lift), tuple(colour)))
        if pattern.white:
            parts.append(Part(f"pattern{k}_white_rects", L.GROUND_PATTERN,
                              _pattern_quads(pattern, list(pattern.white),
                                             lift + _PATTERN_LAYER_M),
                              tuple(pattern.white_color)))
        if pattern.circles:
            discs = []
            for u, v, d in pattern.circles:
                x, _, z = pattern_point(pattern, u, v)
                discs.append(disk(d / 2, lift + 2 * _PATTERN_LAYER_M, (x, z)))
            parts.append(Part(f"pattern{k}_circles", L.GROUND_PATTERN,
                              trimesh.util.concatenate(discs), tuple(pattern.black_color)))
    return parts


def pattern_shade(pattern: GroundPattern, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The pattern's colour at ground points (x, z) of the scene (metres): 0.0 black,
    1.0 white, NaN off the pattern.  Same layout as the meshes (checker, white rectangles
    over it, black discs over everything)."""
    a = math.radians(pattern.yaw_deg)
    dx, dz = np.asarray(x, dtype=np.float64) - pattern.origin[0], np.asarray(z) - pattern.origin[1]
    u = dx * math.cos(a) - dz * math.sin(a)
    v = dx * math.sin(a) + dz * math.cos(a)
    s = pattern.square_size
    out = np.full(u.shape, np.nan)
    checker = np.where((np.floor(u / s) + np.floor(v / s)) % 2 == 0, 0.0, 1.0)
    for u0, v0, u1, v1 in pattern.checker:
        inside = (u >= u0) & (u < u1) & (v >= v0) & (v < v1)
        out[inside] = checker[inside]
    for u0, v0, u1, v1 in pattern.white:
        out[(u >= u0) & (u < u1) & (v >= v0) & (v < v1)] = 1.0
    for cu, cv, d in pattern.circles:
        out[(u - cu) ** 2 + (v - cv) ** 2 < (d / 2) ** 2] = 0.0
    return out


def _pattern_corners(k: int, pattern: GroundPattern) -> list[CheckerCorner]:
    """Inner checker corners of one ground pattern (four whole squares, nothing over them)."""
    s = pattern.square_size
    cells = _pattern_cells(pattern)
    a, b = pattern_axes(pattern)

    def whole(i: int, j: int) -> bool:
        box = cells.get((i, j))
        if box is None:
            return False
        full = (i * s, j * s, (i + 1) * s, (j + 1) * s)
        return all(abs(x - y) < 1e-9 for x, y in zip(box, full))

    def covered(u0: float, v0: float, u1: float, v1: float) -> bool:
        for w0, x0, w1, x1 in pattern.white:
            if w0 < u1 - 1e-9 and w1 > u0 + 1e-9 and x0 < v1 - 1e-9 and x1 > v0 + 1e-9:
                return True
        for cu, cv, d in pattern.circles:
            nu, nv = min(max(cu, u0), u1), min(max(cv, v0), v1)
            if math.hypot(cu - nu, cv - nv) < d / 2 + 1e-9:
                return True
        return False

    out = []
    for i, j in sorted(cells):
        # Corner (i, j) is the square (i, j)'s lower-left corner.
        if not all(whole(i + di, j + dj) for di in (-1, 0) for dj in (-1, 0)):
            continue
        if covered((i - 1) * s, (j - 1) * s, (i + 1) * s, (j + 1) * s):
            continue
        p = pattern_point(pattern, i * s, j * s, PATTERN_LIFT_M)
        out.append(CheckerCorner(f"pattern{k}_{i}_{j}", tuple(float(x) for x in p),
                                 tuple(float(x) for x in a), tuple(float(x) for x in b), s,
                                 L.GROUND_PATTERN, (i + j) % 2 == 0))
    return out


def checker_corners(scene: Scene) -> list[CheckerCorner]:
    """Every inner checker corner of the scene: the pattern board's and the ground
    patterns'.  These are the landmarks ``rvmsim validate`` finds in real captures
    (saddle points refine to subpixel without bias).  Visibility is not checked here."""
    out: list[CheckerCorner] = []
    board = scene.test_site.board
    if board.enabled:
        _, a, b, _ = board_frame(board)
        w, h = board.size
        s = board.square_size
        a0, b0 = -w / 2 + board.margin, -h / 2 + board.margin
        for i in range(1, board.squares[0]):
            for j in range(1, board.squares[1]):
                p = board_point(board, a0 + i * s, b0 + j * s, _SQUARE_LIFT_M)
                out.append(CheckerCorner(f"board_inner_{i}_{j}", tuple(float(x) for x in p),
                                         tuple(float(x) for x in a), tuple(float(x) for x in b),
                                         s, L.BOARD, (i + j) % 2 == 0))
    for k, pattern in enumerate(scene.test_site.ground_patterns):
        out += _pattern_corners(k, pattern)
    return out


def _ground(scene: Scene) -> Part:
    size = scene.test_site.ground_size
    z0 = -min(10.0, size / 4)
    mesh = _ground_rect(-size / 2, size / 2, z0, z0 + size, 0.0)
    tile = 2.0  # metres per texture repeat
    uv = np.stack([mesh.vertices[:, 0] / tile, mesh.vertices[:, 2] / tile], axis=1)
    mesh.visual = trimesh.visual.TextureVisuals(uv=uv)
    return Part("ground", L.GROUND, mesh, tuple(scene.test_site.ground_color), texture="asphalt")


def build_parts(scene: Scene) -> list[Part]:
    """Every labelled surface of ``scene``: ground, test objects, guidelines, board, body.

    Raises
    ------
    SceneError
        When a mesh file cannot be loaded.
    """
    v = scene.vehicle
    parts = [_ground(scene)]
    parts += _test_objects(scene)
    parts += _guidelines(scene)
    parts += _board(scene)
    parts += _ground_patterns(scene)
    parts += _body_part(scene, "bumper", L.BUMPER, tuple(v.paint))
    parts += _body_part(scene, "garnish", L.GARNISH, GARNISH_COLOR)
    parts += _body_part(scene, "trunk", L.TRUNK, tuple(v.paint))
    for i, extra in enumerate(v.extra):
        mesh = _load_mesh_part(scene, f"vehicle.extra.{i}.mesh", extra)
        color = tuple(extra.color) if extra.color is not None else (0.2, 0.2, 0.2)
        parts.append(Part(f"extra_{i}", L.EXTRA_PART_BASE + i, mesh, color))
    return parts


# ---------------------------------------------------------------------------- landmarks
def site_landmarks(scene: Scene) -> list[Landmark]:
    """Known 3D points of the test site, each with the label of the surface it lies on.

    Returns cylinder top centres, stripe centres and corners (the corners of the F/G lower
    patches, the A–E band edges on the side facing the camera), the pattern board's outer
    corners and inner checker corners, the ground patterns' inner checker corners, and the
    centres of the guidelines.  Whether a point
    is visible from the camera is not checked here.
    """
    site = scene.test_site
    r = site.object_diameter / 2
    hgt = site.object_height
    out: list[Landmark] = []

    def on_cyl(c: tuple[float, float], az_deg: float, h: float) -> tuple[float, float, float]:
        a = math.radians(az_deg)
        return (c[0] + r * math.sin(a), -h, c[1] + r * math.cos(a))

    def radial(az_deg: float) -> tuple[float, float, float]:
        a = math.radians(az_deg)
        return (math.sin(a), 0.0, math.cos(a))

    cam = scene.camera.mount.position
    for letter in L.OBJECT_LETTERS:
        c = site.object_centre(letter)
        if c is None:
            continue
        out.append(Landmark(f"{letter}_top_centre", (c[0], -hgt, c[1]), L.object_body(letter),
                            "interior"))
        if letter in "ABCDE":
            az = math.degrees(math.atan2(cam[0] - c[0], cam[2] - c[1]))
            band0 = hgt - site.stripe_width
            lab = L.object_stripe(letter)
            out.append(Landmark(f"{letter}_stripe_centre", on_cyl(c, az, (band0 + hgt) / 2), lab,
                                "interior", radial(az)))
            out.append(Landmark(f"{letter}_stripe_lower_edge", on_cyl(c, az, band0), lab, "edge",
                                radial(az)))
        else:
            az = stripe_azimuth_deg(scene, letter, c)
            half = math.degrees(site.stripe_width / r) / 2
            ph = site.lower_patch_height
            patch = L.object_patch(letter)
            stripe = L.object_stripe(letter)
            out.append(Landmark(f"{letter}_patch_centre", on_cyl(c, az, ph / 2), patch, "interior",
                                radial(az)))
            out.append(Landmark(f"{letter}_stripe_centre", on_cyl(c, az, (ph + hgt) / 2), stripe,
                                "interior", radial(az)))
            for tag, da, h in (("bl", -half, 0.0), ("br", half, 0.0), ("tl", -half, ph),
                               ("tr", half, ph)):
                out.append(Landmark(f"{letter}_patch_{tag}", on_cyl(c, az + da, h), patch,
                                    "corner", radial(az + da)))
            for tag, da, h in (("left", -half, ph / 2), ("right", half, ph / 2),
                               ("top", 0.0, ph)):
                out.append(Landmark(f"{letter}_patch_{tag}_edge", on_cyl(c, az + da, h), patch,
                                    "edge", radial(az + da)))
            for tag, da in (("tl", -half), ("tr", half)):
                out.append(Landmark(f"{letter}_stripe_{tag}", on_cyl(c, az + da, hgt), stripe,
                                    "corner", radial(az + da)))
    board = site.board
    if board.enabled:
        board_normal = tuple(float(x) for x in board_frame(board)[3])
        w, h = board.size
        for tag, sa, sb in (("00", -w / 2, -h / 2), ("10", w / 2, -h / 2), ("11", w / 2, h / 2),
                            ("01", -w / 2, h / 2)):
            out.append(Landmark(f"board_corner_{tag}", tuple(board_point(board, sa, sb)), L.BOARD,
                                "corner", board_normal))
        for tag, sa, sb in (("bottom", 0.0, -h / 2), ("right", w / 2, 0.0), ("top", 0.0, h / 2),
                            ("left", -w / 2, 0.0)):
            out.append(Landmark(f"board_{tag}_edge", tuple(board_point(board, sa, sb)), L.BOARD,
                                "edge", board_normal))
    # Inner checker corners: the board's, then the ground patterns'.
    out += [Landmark(c.name, c.point, c.label, "interior", c.normal)
            for c in checker_corners(scene)]
    g = site.guidelines
    if g.enabled:
        xm = (g.side_x[0] + g.side_x[1]) / 2
        for n, z in enumerate(g.cross_z, start=1):
            out.append(Landmark(f"guide_cross_{n}_centre", (xm, -GUIDELINE_LIFT_M, z),
                                L.guide_cross(n), "interior"))
        zm = (g.side_z[0] + g.side_z[1]) / 2
        out.append(Landmark("guide_side_neg_x_centre", (g.side_x[0], -GUIDELINE_LIFT_M, zm),
                            L.GUIDE_SIDE_NEG_X, "interior"))
        out.append(Landmark("guide_side_pos_x_centre", (g.side_x[1], -GUIDELINE_LIFT_M, zm),
                            L.GUIDE_SIDE_POS_X, "interior"))
    return out
