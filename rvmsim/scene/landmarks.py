"""Landmarks: known 3D points of the built scene, with the label of the surface they lie on.

:func:`site_landmarks` lists them for tests and for validation against real captures;
:func:`checker_corners` lists the inner checker corners (pattern board, ground patterns) that
``rvmsim validate`` finds in real captures.  Points are in the scene frame, metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import labels as L
from .schema import GroundPattern, Guidelines, PatternBoard, Scene
from .site import (
    BOARD_SQUARE_LIFT_M,
    GUIDELINE_LIFT_M,
    PATTERN_LIFT_M,
    board_frame,
    board_point,
    pattern_axes,
    pattern_cells,
    pattern_point,
    stripe_azimuth_deg,
)

__all__ = ["Landmark", "CheckerCorner", "checker_corners", "site_landmarks"]


Vec3 = tuple[float, float, float]


def _vec3(p: np.ndarray | tuple[float, ...]) -> Vec3:
    """Three plain floats from a 3-vector."""
    return (float(p[0]), float(p[1]), float(p[2]))


def _radial(az_deg: float) -> Vec3:
    """Outward unit normal of a vertical cylinder at azimuth ``az_deg`` (degrees)."""
    a = math.radians(az_deg)
    return (math.sin(a), 0.0, math.cos(a))


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
        return _vec3(np.cross(self.axis_a, self.axis_b))


def _pattern_corners(k: int, pattern: GroundPattern) -> list[CheckerCorner]:
    """Inner checker corners of one ground pattern (four whole squares, nothing over them)."""
    s = pattern.square_size
    cells = pattern_cells(pattern)
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

    out: list[CheckerCorner] = []
    for i, j in sorted(cells):
        # Corner (i, j) is the square (i, j)'s lower-left corner.
        if not all(whole(i + di, j + dj) for di in (-1, 0) for dj in (-1, 0)):
            continue
        if covered((i - 1) * s, (j - 1) * s, (i + 1) * s, (j + 1) * s):
            continue
        p = pattern_point(pattern, i * s, j * s, PATTERN_LIFT_M)
        out.append(CheckerCorner(f"pattern{k}_{i}_{j}", _vec3(p), _vec3(a), _vec3(b), s,
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
                p = board_point(board, a0 + i * s, b0 + j * s, BOARD_SQUARE_LIFT_M)
                out.append(CheckerCorner(f"board_inner_{i}_{j}", _vec3(p), _vec3(a), _vec3(b),
                                         s, L.BOARD, (i + j) % 2 == 0))
    for k, pattern in enumerate(scene.test_site.ground_patterns):
        out += _pattern_corners(k, pattern)
    return out



def _object_landmarks(scene: Scene, letter: str, c: tuple[float, float]) -> list[Landmark]:
    """Landmarks of test object ``letter`` standing at ``c`` = (x, z), metres: its top centre,
    then its A–E band centre and lower edge facing the camera, or its F/G patch and vertical
    stripe (centres, corners, edges)."""
    site = scene.test_site
    r = site.object_diameter / 2
    hgt = site.object_height

    def on_cyl(az_deg: float, h: float) -> Vec3:
        a = math.radians(az_deg)
        return (c[0] + r * math.sin(a), -h, c[1] + r * math.cos(a))

    out = [Landmark(f"{letter}_top_centre", (c[0], -hgt, c[1]), L.object_body(letter),
                    "interior")]
    if letter in "ABCDE":
        cam = scene.fisheye_camera().position  # under a load_state, the loaded camera
        az = math.degrees(math.atan2(cam[0] - c[0], cam[2] - c[1]))
        band0 = hgt - site.stripe_width
        lab = L.object_stripe(letter)
        return out + [
            Landmark(f"{letter}_stripe_centre", on_cyl(az, (band0 + hgt) / 2), lab, "interior",
                     _radial(az)),
            Landmark(f"{letter}_stripe_lower_edge", on_cyl(az, band0), lab, "edge", _radial(az)),
        ]
    az = stripe_azimuth_deg(scene, letter, c)
    half = math.degrees(site.stripe_width / r) / 2
    ph = site.lower_patch_height
    patch, stripe = L.object_patch(letter), L.object_stripe(letter)
    out.append(Landmark(f"{letter}_patch_centre", on_cyl(az, ph / 2), patch, "interior",
                        _radial(az)))
    out.append(Landmark(f"{letter}_stripe_centre", on_cyl(az, (ph + hgt) / 2), stripe,
                        "interior", _radial(az)))
    for tag, da, h in (("bl", -half, 0.0), ("br", half, 0.0), ("tl", -half, ph),
                       ("tr", half, ph)):
        out.append(Landmark(f"{letter}_patch_{tag}", on_cyl(az + da, h), patch, "corner",
                            _radial(az + da)))
    for tag, da, h in (("left", -half, ph / 2), ("right", half, ph / 2), ("top", 0.0, ph)):
        out.append(Landmark(f"{letter}_patch_{tag}_edge", on_cyl(az + da, h), patch, "edge",
                            _radial(az + da)))
    for tag, da in (("tl", -half), ("tr", half)):
        out.append(Landmark(f"{letter}_stripe_{tag}", on_cyl(az + da, hgt), stripe, "corner",
                            _radial(az + da)))
    return out


def _board_outline_landmarks(board: PatternBoard) -> list[Landmark]:
    """The pattern board's four outer corners, then the midpoints of its four edges."""
    normal = _vec3(board_frame(board)[3])
    w, h = board.size
    corners = (("00", -w / 2, -h / 2), ("10", w / 2, -h / 2), ("11", w / 2, h / 2),
               ("01", -w / 2, h / 2))
    edges = (("bottom", 0.0, -h / 2), ("right", w / 2, 0.0), ("top", 0.0, h / 2),
             ("left", -w / 2, 0.0))
    return ([Landmark(f"board_corner_{tag}", _vec3(board_point(board, sa, sb)), L.BOARD,
                      "corner", normal) for tag, sa, sb in corners]
            + [Landmark(f"board_{tag}_edge", _vec3(board_point(board, sa, sb)), L.BOARD, "edge",
                        normal) for tag, sa, sb in edges])


def _guideline_landmarks(g: Guidelines) -> list[Landmark]:
    """Centres of the cross guidelines (1, 2, …), then of the two side lines."""
    xm = (g.side_x[0] + g.side_x[1]) / 2
    zm = (g.side_z[0] + g.side_z[1]) / 2
    y = -GUIDELINE_LIFT_M
    out = [Landmark(f"guide_cross_{n}_centre", (xm, y, z), L.guide_cross(n), "interior")
           for n, z in enumerate(g.cross_z, start=1)]
    out.append(Landmark("guide_side_neg_x_centre", (g.side_x[0], y, zm), L.GUIDE_SIDE_NEG_X,
                        "interior"))
    out.append(Landmark("guide_side_pos_x_centre", (g.side_x[1], y, zm), L.GUIDE_SIDE_POS_X,
                        "interior"))
    return out


def site_landmarks(scene: Scene) -> list[Landmark]:
    """Known 3D points of the test site, each with the label of the surface it lies on.

    Returns
    -------
    list of Landmark
        Cylinder top centres, stripe centres and corners (the corners of the F/G lower
        patches, the A–E band edges on the side facing the camera), the pattern board's outer
        corners and edge midpoints and inner checker corners, the ground patterns' inner
        checker corners, and the centres of the guidelines, in that order.

    Convention
    ----------
    Points in the scene frame, metres (:mod:`rvmsim.camera.mount`).  Whether a point is
    visible from the camera is not checked here.
    """
    site = scene.test_site
    out: list[Landmark] = []
    for letter in L.OBJECT_LETTERS:
        c = site.object_centre(letter)
        if c is not None:
            out += _object_landmarks(scene, letter, c)
    if site.board.enabled:
        out += _board_outline_landmarks(site.board)
    # Inner checker corners: the board's, then the ground patterns'.
    out += [Landmark(c.name, c.point, c.label, "interior", c.normal)
            for c in checker_corners(scene)]
    if scene.guidelines_shown:
        out += _guideline_landmarks(site.guidelines)
    return out
