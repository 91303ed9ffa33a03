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

__all__ = ["CubeLayout", "FaceCrop", "CameraRays", "cube_layout", "cover_layout", "refold_layout",
           "refold_coords",
           "face_coords", "face_rotation", "FACE_NAMES", "GUARD_PX"]

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


_FACE_ROTATIONS = np.stack([face_rotation(f) for f in range(6)])
# each face camera's x (y) axis is a signed cube axis: its index and sign
_FACE_X_AXIS = np.argmax(np.abs(_FACE_ROTATIONS[:, :, 0]), axis=1)
_FACE_Y_AXIS = np.argmax(np.abs(_FACE_ROTATIONS[:, :, 1]), axis=1)
_FACE_X_SIGN = _FACE_ROTATIONS[np.arange(6), _FACE_X_AXIS, 0]
_FACE_Y_SIGN = _FACE_ROTATIONS[np.arange(6), _FACE_Y_AXIS, 1]


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
    # a face camera's x and y axes are ± cube axes: pick and sign (no per-face masks)
    px = np.take_along_axis(d, _FACE_X_AXIS[face][..., None], axis=-1)[..., 0]
    py = np.take_along_axis(d, _FACE_Y_AXIS[face][..., None], axis=-1)[..., 0]
    inv = 1.0 / np.abs(comp)
    return face, np.stack([px * (_FACE_X_SIGN[face] * inv), py * (_FACE_Y_SIGN[face] * inv)],
                          axis=-1)


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
        Turn the cube relative to the camera: the seams move, the fisheye image must not.

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


# ---------------------------------------------------------------------------- re-folds
@dataclass(frozen=True)
class CameraRays:
    """A camera's in-field pixel rays as three contiguous float32 components (fast to turn),
    with the flat indices of those pixels and the (H, W) in-field mask."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    index: np.ndarray
    in_fov: np.ndarray

    @staticmethod
    def of(camera: FisheyeCamera, pixels: np.ndarray | None = None) -> CameraRays:
        """The rays of every in-field pixel, or of the in-field ones among ``pixels`` (flat
        indices into the (H, W) image)."""
        rays, in_fov = camera.image_rays()
        index = np.flatnonzero(in_fov)
        if pixels is not None:
            p = np.asarray(pixels, dtype=np.intp)
            index = p[in_fov.ravel()[p]]
        sel = rays.reshape(-1, 3)[index]
        x, y, z = (np.ascontiguousarray(sel[:, i], dtype=np.float32) for i in range(3))
        return CameraRays(x, y, z, index, in_fov)


def _crop_tables(layout: CubeLayout) -> tuple[np.ndarray, ...]:
    """Per face index (6 rows): present, x0, y0, last usable x and y (bilinear reads one
    pixel on), atlas_x0."""
    present = np.zeros(6, bool)
    x0, y0, x1, y1, ax0 = (np.zeros(6, np.float32) for _ in range(5))
    for c in layout.crops:
        present[c.face] = True
        x0[c.face], y0[c.face] = c.x0, c.y0
        x1[c.face], y1[c.face] = c.x0 + c.width - 2, c.y0 + c.height - 2
        ax0[c.face] = c.atlas_x0
    return present, x0, y0, x1, y1, ax0


def refold_coords(cover: CubeLayout, cube_rotation: np.ndarray,
                  rays: CameraRays) -> tuple[np.ndarray, np.ndarray]:
    """The atlas coordinates (x, y; float32, one per ray of ``rays``) where a camera turned
    about its centre samples ``cover``'s atlas: :func:`refold_layout` for chosen pixels only.

    Raises
    ------
    ValueError
        When a ray falls outside the rendered crops.
    """
    m = np.asarray(cube_rotation, dtype=np.float32)
    x = rays.x * m[0, 0] + rays.y * m[1, 0] + rays.z * m[2, 0]
    y = rays.x * m[0, 1] + rays.y * m[1, 1] + rays.z * m[2, 1]
    z = rays.x * m[0, 2] + rays.y * m[1, 2] + rays.z * m[2, 2]
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    on_x = (ax >= ay) & (ax >= az)
    on_y = ~on_x & (ay >= az)
    comp = np.where(on_x, x, np.where(on_y, y, z))
    neg = comp < 0
    sz = np.where(neg, z, -z)  # −sign(comp)·z
    # face cameras (face_rotation): ±x: (∓z, y); +y: (x, −z); −y: (x, z); ±z: (±x, y)
    inv = np.float32(cover.face_size / 2.0) / np.abs(comp)
    u = np.where(on_x, sz, np.where(on_y, x, np.where(neg, -x, x))) * inv
    v = np.where(on_y, sz, y) * inv
    face = (np.where(on_x, 0, np.where(on_y, 2, 4)) + neg).astype(np.uint8)
    present, x0, y0, x1, y1, ax0 = _crop_tables(cover)
    c_px = np.float32(cover.centre_px)
    fx = u + c_px
    fy = v + c_px
    inside = (np.take(present, face) & (fx >= np.take(x0, face)) & (fx <= np.take(x1, face))
              & (fy >= np.take(y0, face)) & (fy <= np.take(y1, face)))
    if not np.all(inside):
        raise ValueError(f"{int(np.sum(~inside))} pixels of the turned camera fall outside the "
                         "rendered cube's crops (cover a larger rotation)")
    return fx + np.take(ax0 - x0, face), fy - np.take(y0, face)


def refold_layout(cover: CubeLayout, cube_rotation: np.ndarray, rays: CameraRays) -> CubeLayout:
    """Where the pixels of a camera turned about its centre sample an already rendered cube.

    Parameters
    ----------
    cover : CubeLayout
        The rendered layout (its faces, crops and face size are kept), e.g. from
        :func:`cover_layout`.
    cube_rotation : (3, 3) float
        The rendered cube's frame relative to the turned camera's frame (``R_camᵀ · R_cube``
        with both camera-to-scene rotations).
    rays : CameraRays
        The turned camera's pixel rays (its lens: :meth:`CameraRays.of`).

    Returns
    -------
    CubeLayout
        ``cover``'s crops with the turned camera's atlas coordinates (fold it with
        :func:`~rvmsim.render.fold` and the rendered atlas).

    Raises
    ------
    ValueError
        When a pixel's ray falls outside the rendered crops (the cube does not cover the
        turned field of view).

    Convention
    ----------
    As :func:`cube_layout`: dst → src atlas coordinates, pixel centres at integer
    coordinates, (−1, −1) outside the lens's field.
    """
    atlas_x_flat, atlas_y_flat = refold_coords(cover, cube_rotation, rays)
    shape = rays.in_fov.shape
    atlas_x = np.full(shape, -1.0, np.float32)
    atlas_y = np.full(shape, -1.0, np.float32)
    atlas_x.ravel()[rays.index] = atlas_x_flat
    atlas_y.ravel()[rays.index] = atlas_y_flat
    return CubeLayout(cover.face_size, cover.crops, atlas_x, atlas_y, rays.in_fov,
                      np.asarray(cube_rotation, dtype=np.float64))


def cover_layout(
    camera: FisheyeCamera,
    rotations: list[np.ndarray],
    *,
    face_size: int | None = None,
    oversample: float = 1.0,
    max_face_size: int = 4096,
    step_px: int = 8,
) -> CubeLayout:
    """A layout whose crops hold the camera's field turned by any of ``rotations`` (and the
    rotations between them, through a margin), for re-folds (:func:`refold_layout`).

    Parameters
    ----------
    camera : FisheyeCamera
    rotations : list of (3, 3) float
        Cube frames relative to the turned camera's frame to cover (the identity is added);
        give a dense set (e.g. a grid over the angle ranges): the crops are the union of
        their footprints, grown by the largest face step between the sampled pixels.
    face_size, oversample, max_face_size
        As :func:`cube_layout` (the automatic size is the unturned camera's).
    step_px : int
        Pixel step of the rays sampled for the footprints.

    Returns
    -------
    CubeLayout
        The unturned camera's layout (cube frame = camera frame) with the covering crops.
    """
    rays, in_fov = camera.image_rays()
    if not np.any(in_fov):
        raise ValueError("no pixel of the camera lies inside the lens's field of view")
    eye = np.eye(3)
    n = face_size
    if n is None:
        face, t = face_coords(rays, eye)
        n = _auto_face_size(face, t, in_fov, camera.width, oversample, max_face_size)
    sub = rays[::step_px, ::step_px]
    sub_fov = in_fov[::step_px, ::step_px]
    face, t = face_coords(sub, eye)
    same = (face[:, 1:] == face[:, :-1]) & sub_fov[:, 1:] & sub_fov[:, :-1]
    same_y = (face[1:, :] == face[:-1, :]) & sub_fov[1:, :] & sub_fov[:-1, :]
    steps = np.concatenate([np.abs(t[:, 1:] - t[:, :-1]).max(axis=-1)[same],
                            np.abs(t[1:, :] - t[:-1, :]).max(axis=-1)[same_y], [0.0]])
    margin = int(np.ceil(n / 2.0 * float(steps.max()))) + 2
    pts = sub[sub_fov]
    full = n + 2 * GUARD_PX
    c_px = GUARD_PX + (n - 1) / 2.0
    lo = np.full((6, 2), np.inf)
    hi = np.full((6, 2), -np.inf)
    for rot in [eye, *rotations]:
        f, tt = face_coords(pts, np.asarray(rot, dtype=np.float64))
        p = n / 2.0 * tt + c_px
        for k in np.unique(f):
            sel = p[f == k]
            lo[k] = np.minimum(lo[k], sel.min(axis=0))
            hi[k] = np.maximum(hi[k], sel.max(axis=0))
    crops: list[FaceCrop] = []
    offset = 0
    for k in range(6):
        if not np.isfinite(lo[k, 0]):
            continue
        x0 = max(int(np.floor(lo[k, 0])) - margin, 0)
        y0 = max(int(np.floor(lo[k, 1])) - margin, 0)
        x1 = min(int(np.ceil(hi[k, 0])) + margin + 2, full)
        y1 = min(int(np.ceil(hi[k, 1])) + margin + 2, full)
        crops.append(FaceCrop(k, x0, y0, x1 - x0, y1 - y0, offset))
        offset += x1 - x0
    empty = CubeLayout(n, tuple(crops), np.zeros((0, 0), np.float32),
                       np.zeros((0, 0), np.float32), in_fov, eye)
    return refold_layout(empty, eye, CameraRays.of(camera))
