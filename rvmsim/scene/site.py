"""The FMVSS No. 111 test site's surfaces: ground, test objects, guidelines, pattern board
and ground patterns, each a labelled :class:`~rvmsim.scene.Part`.

Geometry is in the scene frame (metres, Y toward the ground): a height ``h`` above the
ground is ``y = -h``.  Azimuth on a test object (degrees): 0 faces +Z (away from the car),
90 faces +X (the driver's side), 180 faces the car.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import trimesh

from .. import labels as L
from ..camera import rotation_from_ypr
from .primitives import (Part, concatenate, cylinder_side, disk, ground_rect,
                         ground_strip, quad)
from .schema import GroundPattern, PatternBoard, Rect, Rgb, Scene


__all__ = [
    "site_parts",
    "stripe_azimuth_deg",
    "board_frame",
    "board_point",
    "pattern_point",
    "pattern_axes",
    "pattern_cells",
    "pattern_shade",
    "GUIDELINE_LIFT_M",
    "PAINTED_LINE_LIFT_M",
    "BOARD_LIFT_M",
    "BOARD_SQUARE_LIFT_M",
    "PATTERN_LIFT_M",
]

#: Painted guidelines float this far above the ground (avoids depth fighting), metres.
GUIDELINE_LIFT_M = 0.003
#: Lines painted to check the parking guidelines lie this far above the ground (depth-safe to
#: about 7 m; the check projects them at this height: 1 mm moves a line about 0.3 px of a
#: 1280 × 720 RVM image).
PAINTED_LINE_LIFT_M = 0.001
#: A board lying on the ground: plate thickness; its black squares float a further lift.
BOARD_LIFT_M = 0.006
#: The pattern board's black squares float this far above its plate, metres.
BOARD_SQUARE_LIFT_M = 0.003
#: Ground patterns: the checker lies this far above the ground; white rectangles and black
#: discs lie on top of it, each a further lift up (no depth fighting at 10 m).
PATTERN_LIFT_M = 0.004
_PATTERN_LAYER_M = 0.003

BLACK: Rgb = (0.03, 0.03, 0.03)
WHITE: Rgb = (0.92, 0.92, 0.92)
OBJECT_COLOR: Rgb = (0.93, 0.93, 0.90)


def stripe_azimuth_deg(scene: Scene, letter: str, centre_xz: tuple[float, float]) -> float:
    """Azimuth (degrees) the F/G vertical stripe is centred on.

    Parameters
    ----------
    scene : Scene
        Its ``test_site.vertical_stripe_facing`` says where the stripe faces.
    letter : str
        The object (F or G).
    centre_xz : (float, float)
        The object's axis (x, z), metres.

    Convention
    ----------
    Azimuth about the object's vertical axis: 0 faces +Z (away from the car), 90 faces +X
    (the driver's side), 180 faces the car.
    """
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
    """The FMVSS test objects A–G: body (side and top), stripe and, on F and G, the patch."""
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
            body = concatenate([cylinder_side(r, 0.0, band0, 0, 360, c), top])
            stripe = cylinder_side(r, band0, height, 0, 360, c)
            parts += [
                Part(f"object_{letter}", L.object_body(letter), body, OBJECT_COLOR, smooth=True),
                Part(f"stripe_{letter}", L.object_stripe(letter), stripe, BLACK, smooth=True),
            ]
        else:
            az = stripe_azimuth_deg(scene, letter, c)
            half = math.degrees(site.stripe_width / r) / 2
            rest = cylinder_side(r, 0.0, height, az + half, az + 360 - half, c)
            body = concatenate([rest, top])
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


def _guidelines(scene: Scene) -> list[Part]:
    """The two side guidelines, then the cross lines 1, 2, … (none when disabled)."""
    g = scene.test_site.guidelines
    if not scene.guidelines_shown:
        return []
    hw = g.line_width / 2
    parts: list[Part] = []
    for x, label, name in (
        (g.side_x[0], L.GUIDE_SIDE_NEG_X, "guide_side_neg_x"),
        (g.side_x[1], L.GUIDE_SIDE_POS_X, "guide_side_pos_x"),
    ):
        mesh = ground_rect(x - hw, x + hw, g.side_z[0], g.side_z[1], GUIDELINE_LIFT_M)
        parts.append(Part(name, label, mesh, g.color))
    for n, z in enumerate(g.cross_z, start=1):
        # Cross lines run between the inner edges of the side lines: no overlap, no z-fight.
        mesh = ground_rect(g.side_x[0] + hw, g.side_x[1] - hw, z - hw, z + hw, GUIDELINE_LIFT_M)
        parts.append(Part(f"guide_cross_{n}", L.guide_cross(n), mesh, g.color))
    return parts


def _painted_lines(scene: Scene) -> list[Part]:
    """The lines painted to check the parking guidelines (:attr:`TestSite.painted_lines`):
    flat strips along their polylines, each with its own label."""
    return [Part(f"guide_paint_{line.index}", L.guide_paint(line.index),
                 ground_strip(np.asarray(line.points, np.float64), line.width,
                              PAINTED_LINE_LIFT_M), line.color)
            for line in scene.test_site.painted_lines]


def board_frame(board: PatternBoard) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The frame of the board's front surface.

    Returns
    -------
    centre : (3,) float64
        Centre of the front surface, scene frame, metres.
    a, b, normal : (3,) float64
        Unit vectors: ``a`` along the board's width (its columns), ``b`` along its height
        (its rows), ``normal`` toward the viewer.

    Convention
    ----------
    Scene frame (:mod:`rvmsim.camera.mount`); a board on the ground has ``normal`` = −Y (up)
    and its front surface ``BOARD_LIFT_M`` above the ground.  ``upright`` and ``free``
    boards: ``a``, ``b``, ``normal`` are the columns of
    ``rotation_from_ypr(yaw, pitch, roll)`` applied to +X, −Y and −Z (an upright board
    facing the car when every angle is 0); ``upright`` is ``free`` with pitch = roll = 0.
    """
    c = np.asarray(board.position, dtype=np.float64)
    if board.placement == "ground":
        r = rotation_from_ypr(board.yaw_deg, 0.0, 0.0)
        a, b, nrm = r @ [1.0, 0, 0], r @ [0, 0, 1.0], np.array([0, -1.0, 0])
        c = c + nrm * BOARD_LIFT_M
    else:
        r = rotation_from_ypr(board.yaw_deg, board.pitch_deg, board.roll_deg)
        a, b, nrm = r @ [1.0, 0, 0], r @ [0, -1.0, 0], r @ [0, 0, -1.0]
    return c, a, b, nrm


def board_point(board: PatternBoard, sa: float, sb: float, lift: float = 0.0) -> np.ndarray:
    """Scene point (3,) float64, metres, at board coordinates (``sa``, ``sb``) metres from
    the board centre along ``a`` and ``b`` of :func:`board_frame`, ``lift`` metres in front
    of its surface."""
    c, a, b, nrm = board_frame(board)
    return c + sa * a + sb * b + lift * nrm


def _board(scene: Scene) -> list[Part]:
    """The pattern board: its white plate and its black squares (none when disabled)."""
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
                quad(np.array([board_point(board, sa, sb, BOARD_SQUARE_LIFT_M) for sa, sb in corners]))
            )
    parts = [
        Part("pattern_board", L.BOARD, plate, WHITE),
        Part("pattern_board_squares", L.BOARD, concatenate(squares), BLACK),
    ]
    if board.pattern == "charuco":
        parts.append(Part("pattern_board_markers", L.BOARD, _charuco_markers(board), BLACK))
    return parts


def _charuco_markers(board: PatternBoard) -> trimesh.Trimesh:
    """The black cells of the ChArUco markers, one quad each, in the white squares.

    Convention
    ----------
    As ``cv2.aruco.CharucoBoard`` draws the board: cv2's row r (from the top of its image)
    is the board's row ``squares[1] − 1 − r`` along v, its column c is column c along u;
    marker ids 0, 1, … go through the white squares row by row from cv2's top row.
    """

    d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, board.aruco_dictionary))
    cells = d.markerSize + 2
    assert board.marker_size is not None
    cell = board.marker_size / cells
    s = board.square_size
    w, h = board.size
    a0, b0 = -w / 2 + board.margin, -h / 2 + board.margin
    gap = (s - board.marker_size) / 2
    cols, rows = board.squares
    quads, marker_id = [], 0
    for r in range(rows):
        j = rows - 1 - r
        for i in range(cols):
            if (i + j) % 2 == 0:
                continue  # a black square
            bits = d.generateImageMarker(marker_id, cells)
            marker_id += 1
            u0, v_top = a0 + i * s + gap, b0 + (j + 1) * s - gap
            for mr, mc in zip(*np.nonzero(bits < 128)):
                ua, vb = u0 + mc * cell, v_top - (mr + 1) * cell
                corners = [(ua, vb), (ua + cell, vb), (ua + cell, vb + cell), (ua, vb + cell)]
                quads.append(quad(np.array([board_point(board, sa, sb, 2 * BOARD_SQUARE_LIFT_M)
                                            for sa, sb in corners])))
    return concatenate(quads)


def pattern_point(pattern: GroundPattern, u: float, v: float, lift: float = 0.0) -> np.ndarray:
    """Scene point (3,) float64, metres, at pattern coordinates (``u``, ``v``) metres,
    ``lift`` metres above the ground.

    Convention
    ----------
    The pattern's u axis is the scene's +X and v its +Z when ``yaw_deg`` is 0, from the
    pattern's ``origin`` (an (x, z) ground point of the scene).
    """
    a = math.radians(pattern.yaw_deg)
    x = pattern.origin[0] + u * math.cos(a) + v * math.sin(a)
    z = pattern.origin[1] - u * math.sin(a) + v * math.cos(a)
    return np.array([x, -lift, z])


def pattern_axes(pattern: GroundPattern) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (3,) of the pattern's u and v axes in the scene frame (see
    :func:`pattern_point`)."""
    o = pattern_point(pattern, 0.0, 0.0)
    return pattern_point(pattern, 1.0, 0.0) - o, pattern_point(pattern, 0.0, 1.0) - o


def pattern_cells(pattern: GroundPattern) -> dict[tuple[int, int], tuple[float, float, float, float]]:
    """Checker squares (i, j) → their [u0, v0, u1, v1] (pattern coordinates, metres) after
    clipping to the checker rectangles (a square covered by two rectangles is the union's
    bounding box).  Square (i, j) spans [i·s, (i + 1)·s] × [j·s, (j + 1)·s]; it is black
    when i + j is even."""
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


def _pattern_quads(pattern: GroundPattern, boxes: list[Rect], lift: float) -> trimesh.Trimesh:
    """The rectangles ``boxes`` [u0, v0, u1, v1] of a pattern as one mesh, ``lift`` m up."""
    quads = [
        quad(np.array([pattern_point(pattern, u, v, lift)
                       for u, v in ((u0, v0), (u1, v0), (u1, v1), (u0, v1))]))
        for u0, v0, u1, v1 in boxes
    ]
    return concatenate(quads)


def _ground_patterns(scene: Scene) -> list[Part]:
    """Each ground pattern's black and white checker squares, white rectangles and discs."""
    parts: list[Part] = []
    for k, pattern in enumerate(scene.test_site.ground_patterns):
        cells = pattern_cells(pattern)
        black = [b for (i, j), b in cells.items() if (i + j) % 2 == 0]
        white = [b for (i, j), b in cells.items() if (i + j) % 2 == 1]
        lift = PATTERN_LIFT_M
        for colour, boxes, tag in ((pattern.black_color, black, "black"),
                                   (pattern.white_color, white, "white")):
            if boxes:
                parts.append(Part(f"pattern{k}_{tag}", L.GROUND_PATTERN,
                                  _pattern_quads(pattern, boxes, lift), colour))
        if pattern.white:
            parts.append(Part(f"pattern{k}_white_rects", L.GROUND_PATTERN,
                              _pattern_quads(pattern, list(pattern.white),
                                             lift + _PATTERN_LAYER_M),
                              pattern.white_color))
        if pattern.circles:
            discs: list[trimesh.Trimesh] = []
            for u, v, d in pattern.circles:
                x, _, z = pattern_point(pattern, u, v)
                discs.append(disk(d / 2, lift + 2 * _PATTERN_LAYER_M, (x, z)))
            parts.append(Part(f"pattern{k}_circles", L.GROUND_PATTERN,
                              concatenate(discs), pattern.black_color))
    return parts


def pattern_shade(pattern: GroundPattern, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The pattern's colour at ground points of the scene.

    Parameters
    ----------
    pattern : GroundPattern
    x, z : ndarray
        Ground points of the scene frame, metres (same shape).

    Returns
    -------
    ndarray, float64, shape of ``x``
        0.0 black, 1.0 white, NaN off the pattern.  Same layout as the meshes (checker,
        white rectangles over it, black discs over everything).

    Convention
    ----------
    Pattern coordinates as in :func:`pattern_point`; a rectangle [u0, u1) × [v0, v1)
    includes its lower edges.
    """
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


def _ground(scene: Scene) -> Part:
    """The asphalt ground: a square of ``ground_size`` m, UV-mapped for its texture."""

    size = scene.test_site.ground_size
    z0 = -min(10.0, size / 4)
    mesh = ground_rect(-size / 2, size / 2, z0, z0 + size, 0.0)
    tile = 2.0  # metres per texture repeat
    uv = np.stack([mesh.vertices[:, 0] / tile, mesh.vertices[:, 2] / tile], axis=1)
    mesh.visual = trimesh.visual.TextureVisuals(uv=uv)
    return Part("ground", L.GROUND, mesh, scene.test_site.ground_color, texture="asphalt")


def _site_objects(scene: Scene) -> list[Part]:
    """The objects of a site definition other than FMVSS 111's (:mod:`.sitedefs`): each
    cylinder's side below its band, its marked top band (black) and its top face."""
    parts: list[Part] = []
    for obj in scene.test_site.site_objects:
        body_label, band_label, top_label = obj.labels
        c, r, h = (obj.x, obj.z), obj.radius, obj.height
        body_top = h - obj.top_band
        parts.append(Part(f"site_{obj.name}", body_label,
                          cylinder_side(r, 0.0, body_top, 0, 360, c), OBJECT_COLOR, smooth=True))
        if obj.top_band > 0:
            parts.append(Part(f"site_{obj.name}_band", band_label,
                              cylinder_side(r, body_top, h, 0, 360, c), BLACK, smooth=True))
        parts.append(Part(f"site_{obj.name}_top", top_label, disk(r, h, c), OBJECT_COLOR))
    return parts


def site_parts(scene: Scene) -> list[Part]:
    """Every labelled surface of the test site: ground, test objects, guidelines, pattern
    board and ground patterns, in that order (at a site other than FMVSS 111's: ground and
    the site's objects)."""
    parts = [_ground(scene)]
    parts += _site_objects(scene)
    parts += _test_objects(scene)
    parts += _guidelines(scene)
    parts += _painted_lines(scene)
    parts += _board(scene)
    parts += _ground_patterns(scene)
    return parts
