"""The cube a fisheye image is rendered through: which faces a camera needs, the part of each
face it uses (the crops), and where every fisheye pixel samples them.

Every fisheye pixel centre is back-projected to a ray in the camera frame
(:meth:`~rvmsim.camera.FisheyeCamera.pixel_rays`) and assigned to the face of a cube centred
at the camera whose axis is the ray's dominant component.  Only the faces some ray hits are
rendered (a 190° lens needs five, a narrow lens one), and of each only the rectangle the
rays use; the crops lie side by side in one *atlas* image.

Conventions
-----------
Face images use OpenCV's pixel-centre convention: a face of N px (+ guard g on every side)
has focal length N/2 px and principal point g + (N − 1)/2.  Face cameras follow OpenCV's
axes (x right, y down, z forward) in the cube frame, which is the camera frame unless a
``cube_rotation`` turns it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import FisheyeCamera

__all__ = ["CubeLayout", "FaceCrop", "cube_layout", "face_coords", "face_rotation", "FACE_NAMES",
           "GUARD_PX"]

FACE_NAMES = ("+x", "-x", "+y", "-y", "+z", "-z")
_FACE_AXES = (  # (axis index, sign) of each face's viewing direction in the cube frame
    (0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)
)
#: Guard band around every face, px, so bilinear sampling never reads past a face's edge.
GUARD_PX = 2


def face_rotation(face: int) -> np.ndarray:
    """The orientation of cube face ``face`` (an index into :data:`FACE_NAMES`).

    Returns
    -------
    (3, 3) float64
        Columns: the face camera's x, y, z axes (OpenCV convention: x right, y down, z the
        viewing direction) in the cube frame.
    """
    axis, sign = _FACE_AXES[face]
    z = np.zeros(3)
    z[axis] = sign
    y = np.array([0.0, 1.0, 0.0]) if axis != 1 else np.array([0.0, 0.0, -sign])
    x = np.cross(y, z)
    return np.stack([x, y, z], axis=1)


@dataclass(frozen=True)
class FaceCrop:
    """The part of one cube face that the fisheye image uses.

    ``x0, y0, width, height`` are in the face's pixel grid (N + 2·GUARD_PX square, OpenCV
    pixel centres); ``atlas_x0`` is where the crop starts in the atlas (crops side by side).
    """

    face: int
    x0: int
    y0: int
    width: int
    height: int
    atlas_x0: int


@dataclass(frozen=True)
class CubeLayout:
    """Where each fisheye pixel samples the cube.

    Attributes
    ----------
    face_size : int
        N, the face's inner size in px (a full face image is N + 2·GUARD_PX square).
    crops : tuple of FaceCrop
        The faces that are rendered (only the rectangle the fisheye image uses), in atlas
        order.
    atlas_x, atlas_y : (H, W) float32
        Coordinates of each fisheye pixel in the atlas (crops side by side), for cv2.remap.
    in_fov : (H, W) bool
        Pixels inside the lens's field.
    cube_rotation : (3, 3) float
        Cube frame relative to the camera frame (identity unless seams are being moved).
    """

    face_size: int
    crops: tuple[FaceCrop, ...]
    atlas_x: np.ndarray
    atlas_y: np.ndarray
    in_fov: np.ndarray
    cube_rotation: np.ndarray

    @property
    def faces(self) -> tuple[int, ...]:
        """Indices (into :data:`FACE_NAMES`) of the rendered faces, in atlas order."""
        return tuple(c.face for c in self.crops)

    @property
    def atlas_shape(self) -> tuple[int, int]:
        """(rows, columns) of the atlas, px: the crops side by side."""
        return (max(c.height for c in self.crops), sum(c.width for c in self.crops))

    @property
    def centre_px(self) -> float:
        """Principal point of every face (both axes), pixel-centre convention."""
        return GUARD_PX + (self.face_size - 1) / 2.0


def face_coords(rays: np.ndarray, cube_rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cube face each ray hits, and where on it.

    Parameters
    ----------
    rays : (..., 3) float
        Directions in the camera frame.
    cube_rotation : (3, 3) float
        Cube frame relative to the camera frame.

    Returns
    -------
    face : (...) int
        Index into :data:`FACE_NAMES`: the face whose axis is the ray's dominant component.
    t : (..., 2) float
        Normalised coordinates on that face, (x/z, y/z) in [−1, 1] of its face camera.

    Convention
    ----------
    Face cameras as :func:`face_rotation`; a face of N px puts ``t`` at
    ``N/2 · t + GUARD_PX + (N − 1)/2`` px (pixel centres at integer coordinates).
    """
    d = rays @ cube_rotation  # into the cube frame
    axis = np.argmax(np.abs(d), axis=-1)
    comp = np.take_along_axis(d, axis[..., None], axis=-1)[..., 0]
    face = 2 * axis + (comp < 0)
    pf = np.empty_like(d)
    for f in range(6):
        sel = face == f
        if np.any(sel):
            pf[sel] = d[sel] @ face_rotation(f)
    return face, pf[..., :2] / pf[..., 2:3]


def _auto_face_size(face: np.ndarray, t: np.ndarray, in_fov: np.ndarray, width: int,
                    oversample: float, max_face_size: int) -> int:
    """The face size (px) at which every face is ``oversample`` × as dense as the fisheye
    image (``width`` px wide) where it is least dense, within [16, ``max_face_size``].

    ``face`` (H, W) and ``t`` (H, W, 2) are :func:`face_coords` of the fisheye pixels.
    """
    # Displacement of the unit-focal face coordinate between neighbouring fisheye pixels:
    # a face of N px (focal N/2) has ≥ 1 px per fisheye px where N ≥ 2 / |d|.
    same_x = (face[:, 1:] == face[:, :-1]) & in_fov[:, 1:] & in_fov[:, :-1]
    same_y = (face[1:, :] == face[:-1, :]) & in_fov[1:, :] & in_fov[:-1, :]
    dx = np.linalg.norm(t[:, 1:] - t[:, :-1], axis=-1)[same_x]
    dy = np.linalg.norm(t[1:, :] - t[:-1, :], axis=-1)[same_y]
    steps = np.concatenate([dx, dy])
    min_step = float(np.min(steps)) if steps.size else 2.0 / width
    face_size = int(min(max_face_size, math.ceil(2.0 * oversample / min_step)))
    return max(face_size, 16)


def cube_layout(
    camera: FisheyeCamera,
    *,
    face_size: int | None = None,
    oversample: float = 1.0,
    max_face_size: int = 4096,
    cube_rotation: np.ndarray | None = None,
) -> CubeLayout:
    """Decide which cube faces a camera needs, their size, and the fold-back map.

    Parameters
    ----------
    camera : FisheyeCamera
        The fisheye camera.
    face_size : int, optional
        Face size in px.  By default, ``oversample`` × the smallest size at which every face
        is at least as dense as the fisheye image in both directions (capped at
        ``max_face_size``).
    oversample : float
        Face pixels per fisheye pixel (at the least dense place) for the automatic size.
        Nearest sampling puts a label border within 0.5 / oversample px of its true place.
    max_face_size : int
        Upper bound for the automatic size.
    cube_rotation : (3, 3) float, optional
        Turn the cube relative to the camera (moves the seams; used by tests).

    Returns
    -------
    CubeLayout

    Raises
    ------
    ValueError
        When no pixel of the camera lies inside its lens's field of view.

    Convention
    ----------
    ``atlas_x``/``atlas_y`` map each fisheye pixel to the atlas (dst → src, as cv2.remap
    reads them); pixel centres at integer coordinates in both images.  Pixels outside the
    lens's field map to (−1, −1).
    """
    rot = np.eye(3) if cube_rotation is None else np.asarray(cube_rotation, dtype=np.float64)
    rays, in_fov = camera.image_rays()
    face, t = face_coords(rays, rot)
    if not np.any(in_fov):
        raise ValueError("no pixel of the camera lies inside the lens's field of view")
    n = face_size if face_size is not None else _auto_face_size(
        face, t, in_fov, camera.width, oversample, max_face_size)
    c_px = GUARD_PX + (n - 1) / 2.0
    full = n + 2 * GUARD_PX
    fx = n / 2.0 * t[..., 0] + c_px
    fy = n / 2.0 * t[..., 1] + c_px
    crops: list[FaceCrop] = []
    atlas_x = np.full(face.shape, -1.0, np.float32)
    atlas_y = np.full(face.shape, -1.0, np.float32)
    offset = 0
    for f in (int(x) for x in np.unique(face[in_fov])):
        sel = (face == f) & in_fov
        # Bilinear sampling reads one pixel beyond the sample: keep one more for safety.
        x0 = max(int(np.floor(fx[sel].min())) - 1, 0)
        x1 = min(int(np.ceil(fx[sel].max())) + 2, full)
        y0 = max(int(np.floor(fy[sel].min())) - 1, 0)
        y1 = min(int(np.ceil(fy[sel].max())) + 2, full)
        crops.append(FaceCrop(f, x0, y0, x1 - x0, y1 - y0, offset))
        atlas_x[sel] = fx[sel] - x0 + offset
        atlas_y[sel] = fy[sel] - y0
        offset += x1 - x0
    return CubeLayout(n, tuple(crops), atlas_x, atlas_y, in_fov, rot)
