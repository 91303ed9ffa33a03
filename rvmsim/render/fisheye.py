"""Render the rear-view camera's fisheye image (colour + labels) with pyrender off-screen.

Method
------
1. Every fisheye pixel centre is back-projected to a ray in the camera frame
   (:meth:`FisheyeCamera.pixel_rays`).
2. The rays are assigned to the faces of a cube centred at the camera (the face whose axis is
   the ray's dominant component).  Only the faces some ray hits are rendered: a 190° lens
   needs five, a narrow lens one.
3. Each needed face is rendered twice by pyrender as a 90° pinhole view with a 2 px guard band
   (so bilinear sampling never reads past a face's edge): a lit colour pass (MSAA) and a
   segmentation pass (flat label colours, no lighting, no multisampling).
4. The faces are folded into the fisheye image: colour with ``cv2.remap`` (bilinear) from a
   face atlas, labels by nearest sampling of the same coordinates (IDs are never blended).

Conventions
-----------
Face images use OpenCV's pixel-centre convention: a face of N px (+ guard g) has focal length
N/2 px and principal point g + (N − 1)/2.  Fisheye pixels outside the lens's field are
labelled ``VOID`` and black; inside it, pixels where no geometry is hit are ``SKY``.

The headless GL platform is EGL unless ``PYOPENGL_PLATFORM`` says otherwise (``osmesa``).
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from .. import labels as L
from ..camera import FisheyeCamera
from ..scene import Part, build_parts
from ..scene import Scene

__all__ = ["FisheyeImages", "CubeLayout", "FaceCrop", "cube_layout", "render_fisheye", "FACE_NAMES"]

FACE_NAMES = ("+x", "-x", "+y", "-y", "+z", "-z")
_FACE_AXES = (  # (axis index, sign) of each face's viewing direction in the cube frame
    (0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)
)
GUARD_PX = 2
Z_NEAR_M = 0.003
Z_FAR_M = 400.0


def _face_rotation(face: int) -> np.ndarray:
    """Columns: the face camera's x, y, z axes (OpenCV convention) in the cube frame."""
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
        return tuple(c.face for c in self.crops)

    @property
    def atlas_shape(self) -> tuple[int, int]:
        return (max(c.height for c in self.crops), sum(c.width for c in self.crops))

    @property
    def centre_px(self) -> float:
        """Principal point of every face (both axes), pixel-centre convention."""
        return GUARD_PX + (self.face_size - 1) / 2.0


def _face_coords(rays: np.ndarray, cube_rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Face index and normalised face coords (x/z, y/z in [-1, 1]) for camera rays (..., 3)."""
    d = rays @ cube_rotation  # into the cube frame
    axis = np.argmax(np.abs(d), axis=-1)
    comp = np.take_along_axis(d, axis[..., None], axis=-1)[..., 0]
    face = 2 * axis + (comp < 0)
    pf = np.empty_like(d)
    for f in range(6):
        sel = face == f
        if np.any(sel):
            pf[sel] = d[sel] @ _face_rotation(f)
    return face, pf[..., :2] / pf[..., 2:3]


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
    """
    rot = np.eye(3) if cube_rotation is None else np.asarray(cube_rotation, dtype=np.float64)
    rays, in_fov = camera.image_rays()
    face, t = _face_coords(rays, rot)
    if not np.any(in_fov):
        raise ValueError("no pixel of the camera lies inside the lens's field of view")
    if face_size is None:
        # Displacement of the unit-focal face coordinate between neighbouring fisheye pixels:
        # a face of N px (focal N/2) has ≥ 1 px per fisheye px where N ≥ 2 / |d|.
        same_x = (face[:, 1:] == face[:, :-1]) & in_fov[:, 1:] & in_fov[:, :-1]
        same_y = (face[1:, :] == face[:-1, :]) & in_fov[1:, :] & in_fov[:-1, :]
        dx = np.linalg.norm(t[:, 1:] - t[:, :-1], axis=-1)[same_x]
        dy = np.linalg.norm(t[1:, :] - t[:-1, :], axis=-1)[same_y]
        steps = np.concatenate([dx, dy])
        min_step = float(np.min(steps)) if steps.size else 2.0 / camera.width
        face_size = int(min(max_face_size, math.ceil(2.0 * oversample / min_step)))
        face_size = max(face_size, 16)
    n = face_size
    c_px = GUARD_PX + (n - 1) / 2.0
    full = n + 2 * GUARD_PX
    fx = n / 2.0 * t[..., 0] + c_px
    fy = n / 2.0 * t[..., 1] + c_px
    crops = []
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


@dataclass(frozen=True)
class FisheyeImages:
    """The rendered fisheye frame.

    Attributes
    ----------
    color : (H, W, 3) uint8
        Lit, textured sRGB-ish colour image.
    labels : (H, W) uint8
        One label ID per pixel (:mod:`rvmsim.labels`), exact: no blending.
    camera : FisheyeCamera
        The camera the images were rendered for.
    timings : dict
        Seconds spent per stage (``meshes``, ``gl_setup``, ``faces``, ``fold``).
    face_size : int
        Cube face size used, px.
    faces : tuple of str
        Names of the cube faces rendered.
    """

    color: np.ndarray
    labels: np.ndarray
    camera: FisheyeCamera
    timings: dict = field(default_factory=dict)
    face_size: int = 0
    faces: tuple = ()


def _asphalt_texture(size: int = 256, seed: int = 7) -> np.ndarray:
    """Procedural asphalt: grey speckle with soft blotches, tileable, uint8 RGB."""
    rng = np.random.default_rng(seed)
    fine = rng.normal(0.0, 1.0, (size, size))
    coarse = rng.normal(0.0, 1.0, (size // 16, size // 16))
    coarse = np.kron(coarse, np.ones((16, 16)))
    # Periodic Gaussian blur through the FFT keeps the texture tileable.
    freq = np.fft.fftfreq(size)
    gauss = np.exp(-2 * (np.pi * 6.0) ** 2 * (freq[:, None] ** 2 + freq[None, :] ** 2))
    coarse = np.real(np.fft.ifft2(np.fft.fft2(coarse) * gauss))
    img = 0.8 + 0.10 * fine + 0.12 * coarse / (coarse.std() + 1e-9)
    img = np.clip(img, 0.4, 1.0)
    return (np.repeat(img[..., None], 3, axis=2) * 255).astype(np.uint8)


def _ensure_gl_platform() -> None:
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")


#: Lights baked into vertex colours: (direction the light travels, scene frame; intensity).
#: An overcast-daylight set-up: a sun from above and behind the car and a weak fill.
LIGHTS = (
    (np.array([0.25, 1.0, 0.45]), 0.62),
    (np.array([-0.3, 0.4, -1.0]), 0.18),
)
AMBIENT = 0.38


def _lambert(normals: np.ndarray) -> np.ndarray:
    """Irradiance factor (ambient + Lambertian) for unit normals (N, 3)."""
    shade = np.full(len(normals), AMBIENT)
    for direction, intensity in LIGHTS:
        to_light = -direction / np.linalg.norm(direction)
        shade += intensity * np.clip(normals @ to_light, 0.0, None)
    return shade


def _linear_to_srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _primitive(part: Part, texture: object | None) -> object:
    """A pyrender primitive with lighting baked into vertex colours (rendered FLAT: the GL
    lighting shader is the slow part on llvmpipe, and the scene's lights never move)."""
    import pyrender

    m = part.mesh
    if part.smooth:
        positions, normals, indices = m.vertices, m.vertex_normals, m.faces
        uv = None
    else:
        positions = m.vertices[m.faces].reshape(-1, 3)
        normals = np.repeat(m.face_normals, 3, axis=0)
        indices = None
        uv = None
    if texture is not None:
        uv_src = np.asarray(m.visual.uv)
        uv = uv_src if part.smooth else uv_src[m.faces].reshape(-1, 2)
    linear = np.asarray(part.color)[None, :] * _lambert(np.asarray(normals))[:, None]
    rgba = np.concatenate([_linear_to_srgb(linear), np.ones((len(linear), 1))], axis=1)
    material = pyrender.MetallicRoughnessMaterial(
        baseColorFactor=[1.0, 1.0, 1.0, 1.0],
        baseColorTexture=texture,
        doubleSided=True,
    )
    return pyrender.Primitive(
        positions=np.asarray(positions, dtype=np.float32),
        normals=np.asarray(normals, dtype=np.float32),
        texcoord_0=None if uv is None else np.asarray(uv, dtype=np.float32),
        color_0=rgba.astype(np.float32),
        indices=None if indices is None else np.asarray(indices, dtype=np.uint32),
        material=material,
    )


def _pyrender_scene(parts: list[Part], sky: tuple) -> tuple[object, dict]:
    import pyrender

    sky_srgb = _linear_to_srgb(np.asarray(sky, dtype=np.float64))
    scene = pyrender.Scene(bg_color=[*sky_srgb, 1.0])
    seg: dict = {}
    textures: dict = {}
    for part in parts:
        tex = None
        if part.texture is not None:
            if part.texture not in textures:
                textures[part.texture] = pyrender.Texture(
                    source=_asphalt_texture(), source_channels="RGB"
                )
            tex = textures[part.texture]
        node = scene.add(pyrender.Mesh([_primitive(part, tex)]), name=part.name)
        seg[node] = np.array([part.label & 0xFF, part.label >> 8, 0])
    return scene, seg


_GL_FROM_CV = np.diag([1.0, -1.0, -1.0])


def render_fisheye(
    scene: Scene,
    *,
    camera: FisheyeCamera | None = None,
    face_size: int | None = None,
    cube_rotation: np.ndarray | None = None,
    progress: bool = False,
) -> FisheyeImages:
    """Render the fisheye colour and label images of a scene.

    Parameters
    ----------
    scene : Scene
        The vehicle and test site.
    camera : FisheyeCamera, optional
        Camera to render with; default ``scene.fisheye_camera()``.  Pass
        ``scene.fisheye_camera().scaled(0.25)`` for a quick small render.
    face_size : int, optional
        Cube face size (px); default from ``scene.render.face_size_px`` or automatic.
    cube_rotation : (3, 3) float, optional
        Turn the cube about the camera (moves the seams; for tests).
    progress : bool
        Show a progress bar over the cube faces.

    Returns
    -------
    FisheyeImages
    """
    t0 = time.perf_counter()
    cam = scene.fisheye_camera() if camera is None else camera
    parts = build_parts(scene)
    layout = cube_layout(
        cam,
        face_size=face_size or scene.render.face_size_px,
        oversample=scene.render.oversample,
        max_face_size=scene.render.max_face_size_px,
        cube_rotation=cube_rotation,
    )
    t1 = time.perf_counter()

    _ensure_gl_platform()
    import pyrender

    pscene, seg = _pyrender_scene(parts, tuple(scene.render.sky_color))
    half = layout.face_size / 2.0
    first = layout.crops[0]
    renderer = pyrender.OffscreenRenderer(first.width, first.height)
    cam_node = None
    t2 = time.perf_counter()
    atlas_h, atlas_w = layout.atlas_shape
    color_atlas = np.zeros((atlas_h, atlas_w, 3), np.uint8)
    label_atlas = np.zeros((atlas_h, atlas_w), np.uint8)
    crops = layout.crops
    if progress:
        from tqdm import tqdm

        crops = tqdm(crops, desc="render cube faces", unit="face", leave=False)
    flags = pyrender.RenderFlags
    try:
        for crop in crops:
            # pyrender's principal point counts from pixel edges: OpenCV centre + 0.5.
            gl_cam = pyrender.IntrinsicsCamera(
                fx=half, fy=half,
                cx=layout.centre_px + 0.5 - crop.x0, cy=layout.centre_px + 0.5 - crop.y0,
                znear=Z_NEAR_M, zfar=Z_FAR_M,
            )
            pose = np.eye(4)
            pose[:3, :3] = (
                cam.rotation @ layout.cube_rotation @ _face_rotation(crop.face) @ _GL_FROM_CV
            )
            pose[:3, 3] = cam.position
            if cam_node is not None:
                pscene.remove_node(cam_node)
            cam_node = pscene.add(gl_cam, pose=pose)
            renderer.viewport_width, renderer.viewport_height = crop.width, crop.height
            color, _ = renderer.render(pscene, flags=flags.FLAT | flags.SKIP_CULL_FACES)
            seg_img, _ = renderer.render(
                pscene, flags=flags.SEG | flags.SKIP_CULL_FACES, seg_node_map=seg
            )
            cols = slice(crop.atlas_x0, crop.atlas_x0 + crop.width)
            color_atlas[: crop.height, cols] = color[..., :3]
            label_atlas[: crop.height, cols] = seg_img[..., 0]
    finally:
        renderer.delete()
    t3 = time.perf_counter()

    import cv2

    color = cv2.remap(
        color_atlas, layout.atlas_x, layout.atlas_y, cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT, borderValue=0,
    )
    # Nearest sampling done explicitly: round half up, then plain indexing (exact IDs).
    ix = np.floor(layout.atlas_x + 0.5).astype(np.intp)
    iy = np.floor(layout.atlas_y + 0.5).astype(np.intp)
    np.clip(ix, 0, label_atlas.shape[1] - 1, out=ix)
    np.clip(iy, 0, label_atlas.shape[0] - 1, out=iy)
    labels = label_atlas[iy, ix]
    labels = np.where(labels == 0, L.SKY, labels).astype(np.uint8)
    labels[~layout.in_fov] = L.VOID
    color[~layout.in_fov] = 0
    t4 = time.perf_counter()
    return FisheyeImages(
        color=color,
        labels=labels,
        camera=cam,
        timings={"meshes": t1 - t0, "gl_setup": t2 - t1, "faces": t3 - t2, "fold": t4 - t3},
        face_size=layout.face_size,
        faces=tuple(FACE_NAMES[f] for f in layout.faces),
    )
