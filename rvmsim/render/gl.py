"""Render the cube faces with pyrender off-screen: the GL scene, its lighting, the faces.

Each needed face (:mod:`rvmsim.render.cube`) is rendered twice as a 90° pinhole view of its
crop: a lit colour pass and a segmentation pass (flat label colours, no lighting, no
multisampling, every triangle in both windings: exact labels by construction).  The meshes
are drawn in the parts' order in every process (the depth test's ties go to the part listed
first), so a scene renders to the same bits in every process.  Lighting is baked into
vertex colours (an overcast daylight: a sun from above and behind the car, a weak fill and
ambient light), so the colour pass is drawn FLAT.

Conventions
-----------
Face cameras are placed at the camera's optical centre with the face's orientation
(:func:`~rvmsim.render.cube.face_rotation`) in the scene frame; pyrender's principal point
counts from pixel edges, so it is OpenCV's pixel-centre value + 0.5.  The headless GL
platform is EGL unless ``PYOPENGL_PLATFORM`` says otherwise (``osmesa``).
"""

from __future__ import annotations

import multiprocessing as mp
import time
from collections.abc import Iterable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from contextvars import ContextVar, Token
from dataclasses import dataclass
from types import TracebackType
from typing import TYPE_CHECKING, Any

import numpy as np

from .._optional import import_pyrender
from .._procs import start_pool, start_worker_server, stop_pool, stop_requested
from .._progress import progress_bar
from ..camera import FisheyeCamera
from ..errors import RvmsimError
from ..scene import Part
from .cube import CubeLayout, FaceCrop, face_rotation

if TYPE_CHECKING:
    import pyrender  # no type information: its classes are Any to mypy

__all__ = ["FaceAtlas", "render_faces", "RenderProcess", "prepare_render", "LIGHTS", "AMBIENT",
           "Z_NEAR_M", "Z_FAR_M"]

#: How many workers a render is tried in before it fails (see :class:`RenderProcess`).
_RENDER_ATTEMPTS = 2

Z_NEAR_M = 0.003
Z_FAR_M = 400.0


def _asphalt_texture(size: int = 256, seed: int = 7) -> np.ndarray:
    """Procedural asphalt: grey speckle with soft blotches, tileable, uint8 RGB."""
    rng = np.random.default_rng(seed)
    fine = rng.normal(0.0, 1.0, (size, size))
    blotches = rng.normal(0.0, 1.0, (size // 16, size // 16))
    coarse: np.ndarray = np.kron(blotches, np.ones((16, 16)))
    # Periodic Gaussian blur through the FFT keeps the texture tileable.
    freq = np.fft.fftfreq(size)
    gauss = np.exp(-2 * (np.pi * 6.0) ** 2 * (freq[:, None] ** 2 + freq[None, :] ** 2))
    coarse = np.real(np.fft.ifft2(np.fft.fft2(coarse) * gauss))
    img = 0.8 + 0.10 * fine + 0.12 * coarse / (coarse.std() + 1e-9)
    img = np.clip(img, 0.4, 1.0)
    return (np.repeat(img[..., None], 3, axis=2) * 255).astype(np.uint8)


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
    """sRGB encoding of linear colour values (clipped to 0–1)."""
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _primitive(part: Part, texture: pyrender.Texture | None) -> pyrender.Primitive:
    """A pyrender primitive with lighting baked into vertex colours (rendered FLAT: the GL
    lighting shader is the slow part on llvmpipe, and the scene's lights never move)."""
    pyrender = import_pyrender()
    m = part.mesh
    positions: np.ndarray
    indices: np.ndarray | None
    uv: np.ndarray | None = None
    if part.smooth:
        positions, normals, indices = m.vertices, m.vertex_normals, m.faces
    else:
        positions = m.vertices[m.faces].reshape(-1, 3)
        normals = np.repeat(m.face_normals, 3, axis=0)
        indices = None
    if texture is not None:
        uv_src = np.asarray(m.visual.uv)  # type: ignore[union-attr]  # textured parts carry UVs
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


def _label_primitive(part: Part) -> pyrender.Primitive:
    """The label pass's primitive of ``part``: its triangles in both windings.

    pyrender's segmentation pass culls back faces whatever the render flags say, while
    the colour pass (double-sided materials) draws them; a surface seen from behind, or a
    mesh whose triangles are not all wound alike (common in CAD exports), would be seen
    in colour but not in the labels.  With each triangle twice, once each way, the copy
    that faces the camera is drawn wherever the colour pass draws the surface.
    """
    pyrender = import_pyrender()
    faces = np.asarray(part.mesh.faces)
    return pyrender.Primitive(
        positions=np.asarray(part.mesh.vertices, dtype=np.float32),
        indices=np.concatenate([faces, faces[:, ::-1]]).astype(np.uint32),
    )


@dataclass(frozen=True)
class _GlScene:
    """The pyrender scene of a part list: the colour meshes, and the label meshes with the
    segmentation colour of each (its label: low byte in red, high byte in green), both in
    the parts' order."""

    scene: Any  # pyrender.Scene
    color_nodes: list[Any]
    seg: dict[Any, np.ndarray]

    def show(self, *, labels: bool) -> None:
        """Make the label meshes (``labels``) or the colour meshes the visible ones."""
        for node in self.seg:
            node.mesh.is_visible = labels
        for node in self.color_nodes:
            node.mesh.is_visible = not labels


def _pyrender_scene(parts: list[Part], sky: tuple[float, float, float]) -> _GlScene:
    """The pyrender scene of ``parts`` (lighting baked, see :func:`_primitive`; labels
    from :func:`_label_primitive`) under a sky of linear colour ``sky``."""
    pyrender = import_pyrender()
    sky_srgb = _linear_to_srgb(np.asarray(sky, dtype=np.float64))
    scene = pyrender.Scene(bg_color=[*sky_srgb, 1.0])
    color_nodes: list[Any] = []
    seg: dict[Any, np.ndarray] = {}  # pyrender.Node -> label colour
    textures: dict[str, Any] = {}  # texture name -> pyrender.Texture
    for part in parts:
        tex = None
        if part.texture is not None:
            if part.texture not in textures:
                textures[part.texture] = pyrender.Texture(
                    source=_asphalt_texture(), source_channels="RGB"
                )
            tex = textures[part.texture]
        color_nodes.append(scene.add(pyrender.Mesh([_primitive(part, tex)]), name=part.name))
        node = scene.add(pyrender.Mesh([_label_primitive(part)]), name=f"{part.name} (labels)")
        seg[node] = np.array([part.label & 0xFF, part.label >> 8, 0])
    return _GlScene(scene, color_nodes, seg)


#: OpenCV camera axes (x right, y down, z forward) → GL camera axes (x right, y up, z back).
_GL_FROM_CV = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class FaceAtlas:
    """The rendered face crops side by side (the layout's atlas).

    Attributes
    ----------
    color : (rows, cols, 3) uint8
        Lit colour, sRGB.
    labels : (rows, cols) uint8
        Label IDs; 0 where no geometry is hit (the sky).
    gl_setup_s, faces_s : float
        Seconds spent building the GL scene and renderer, and rendering the faces.
    """

    color: np.ndarray
    labels: np.ndarray
    gl_setup_s: float
    faces_s: float


def _face_pose(camera: FisheyeCamera, layout: CubeLayout, crop: FaceCrop) -> np.ndarray:
    """(4, 4) GL camera-to-scene pose of the face of ``crop``."""
    pose = np.eye(4)
    pose[:3, :3] = camera.rotation @ layout.cube_rotation @ face_rotation(crop.face) @ _GL_FROM_CV
    pose[:3, 3] = camera.position
    return pose


def render_faces(parts: list[Part], layout: CubeLayout, camera: FisheyeCamera, *, sky: tuple[float, float, float],
                 progress: bool = False, color: bool = True,
                 renders: RenderProcess | None = None) -> FaceAtlas:
    """Render the crops of ``layout`` (colour and labels) for ``camera``.

    In a process of its own (:class:`RenderProcess`; ``renders``: one kept for a block of
    renders, else one for this render): a crash of the OpenGL driver ends that worker, not
    the caller, and the render is tried once more in a fresh one.  A process that is itself a
    worker (a pool's, a Dask cluster's) renders here: it is the disposable one.

    Parameters
    ----------
    parts : list of Part
        The scene's labelled surfaces (:func:`~rvmsim.scene.build_parts`).
    layout : CubeLayout
        Which faces, which crops, and the atlas they go into.
    camera : FisheyeCamera
        Its pose places the cube; its lens is not used here.
    sky : (3,) float
        Background colour, linear 0–1.
    progress : bool
        Show a progress bar over the faces.
    color : bool
        Render the colour pass too (else the colour atlas stays black: labels only, half
        the work).
    renders : RenderProcess, optional
        The worker to render in, kept by the caller for a block of renders (default: that
        of the innermost ``with RenderProcess():`` block around this call in this thread,
        else one for this render).

    Returns
    -------
    FaceAtlas

    Convention
    ----------
    The atlas holds each crop at columns ``[atlas_x0, atlas_x0 + width)`` and rows
    ``[0, height)``, in the face's pixel grid (pixel centres at integer coordinates).
    """
    if mp.parent_process() is not None:
        return _render_here(parts, layout, camera, sky, progress, color)
    renders = renders or _KEPT.get()
    if renders is not None:
        return renders.render(parts, layout, camera, sky, progress, color)
    with RenderProcess() as own:
        return own.render(parts, layout, camera, sky, progress, color)


class RenderProcess:
    """The worker process renders run in, kept for a block of renders::

        with RenderProcess():
            for view in views:
                render_fisheye(scene, camera=view)  # every render of the block in one worker

    Every render of the block (:func:`render_faces`, however deep below the call that
    starts it) runs in this worker, unless it is given another (``renders=``).  The block
    is the ``with`` statement's, in its thread (a :class:`contextvars.ContextVar`): another
    thread renders in the block only when handed the worker (``renders=renders``).  Each
    render after the first skips a fresh process's start (the EGL display and the shaders,
    about 0.13 s).  The worker is a pool of one (:func:`rvmsim._procs.start_pool`:
    it ends with this process however this process ends) and is gone when the block ends:
    nothing of a call keeps running after it returns.  A render whose worker dies is
    rendered again in a fresh one (:data:`_RENDER_ATTEMPTS` in all); a Ctrl-C or SIGTERM
    while it renders stops the worker at once.

    Why a process of its own: llvmpipe has been seen to abort (SIGABRT, inside
    ``glReadPixels``) once in thousands of renders, which ended the caller with it.  A
    render is pure (the same inputs give the same atlas), so a fresh worker's render is the
    same render.
    """

    def __init__(self) -> None:
        self._pool: ProcessPoolExecutor | None = None
        self._blocks: list[Token[RenderProcess | None]] = []
        self._in_flight = 0  # renders under way (another thread's, given renders=)

    def __enter__(self) -> RenderProcess:
        self._blocks.append(_KEPT.set(self))
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        _KEPT.reset(self._blocks.pop())
        if not self._blocks:  # an idle worker ends in order even when the block failed
            self.close(now=exc_type is not None and self._in_flight > 0)

    def close(self, *, now: bool = False) -> None:
        """End the worker (``now``: without waiting for a render in flight)."""
        pool, self._pool = self._pool, None
        if pool is not None:
            stop_pool(pool, now=now)

    def render(self, parts: list[Part], layout: CubeLayout, camera: FisheyeCamera,
               sky: tuple[float, float, float], progress: bool, color: bool) -> FaceAtlas:
        """:func:`render_faces` in the worker."""
        for attempt in range(1, _RENDER_ATTEMPTS + 1):
            if self._pool is None:
                self._pool = start_pool(1)
            self._in_flight += 1
            try:
                atlas: FaceAtlas = self._pool.submit(_render_here, parts, layout, camera, sky,
                                                     progress, color).result()
                return atlas
            except BrokenProcessPool:
                self.close(now=True)
                stop = stop_requested()  # a SIGTERM to the process group ended it
                if stop is not None:
                    raise stop from None
                if attempt == _RENDER_ATTEMPTS:
                    raise RvmsimError(
                        f"render: the OpenGL render process died {attempt} times in a row "
                        "(the driver crashed, or the process was killed)") from None
            except Exception:  # the render's own error: its worker is fine
                raise
            except BaseException:  # Ctrl-C, SIGTERM: the render in flight is abandoned
                self.close(now=True)
                raise
            finally:
                self._in_flight -= 1
        raise AssertionError("unreachable")


#: The worker of the innermost ``with RenderProcess():`` block in this thread, if any.
_KEPT: ContextVar[RenderProcess | None] = ContextVar("rvmsim_render_process", default=None)


def prepare_render() -> None:
    """Start what :func:`render_faces` renders in (the worker fork server,
    :func:`rvmsim._procs.start_worker_server`) now, so that it starts while the caller
    builds the meshes."""
    if mp.parent_process() is None:
        start_worker_server()


def _draw_in_part_order(renderer: pyrender.OffscreenRenderer, nodes: list[Any]) -> None:
    """Make ``renderer`` draw the mesh ``nodes`` in this order, in every process.

    pyrender 0.1.45 draws opaque meshes sorted by their node's distance from the camera,
    and ours all sit at the origin (their vertices are in the scene frame), so the sort
    keeps the order of ``Scene.mesh_nodes``: a set of objects hashed by address, which
    differs from process to process.  Where two surfaces meet or nearly coincide (a
    cylinder's base on the ground, a garnish against the bumper) the depth test keeps the
    fragment drawn first on a tie, so the draw order decided a few label pixels, and through
    multisampling a few colour pixels, differently in each process.  pyrender is pinned
    (pyproject.toml), and its renderer has no option for the order, so its private sort is
    replaced on this renderer.
    """
    rank = {node: i for i, node in enumerate(nodes)}
    inner = renderer._renderer  # pyrender.Renderer: the one that sorts and draws
    inner._sorted_mesh_nodes = lambda scene: sorted(scene.mesh_nodes, key=rank.__getitem__)


def _render_here(parts: list[Part], layout: CubeLayout, camera: FisheyeCamera,
                 sky: tuple[float, float, float], progress: bool, color: bool) -> FaceAtlas:
    """:func:`render_faces` in this process."""
    t0 = time.perf_counter()
    pyrender = import_pyrender()
    gl_scene = _pyrender_scene(parts, sky)
    pscene = gl_scene.scene
    half = layout.face_size / 2.0
    first = layout.crops[0]
    renderer = pyrender.OffscreenRenderer(first.width, first.height)
    _draw_in_part_order(renderer, [*gl_scene.color_nodes, *gl_scene.seg])
    cam_node = None
    t1 = time.perf_counter()
    atlas_h, atlas_w = layout.atlas_shape
    color_atlas = np.zeros((atlas_h, atlas_w, 3), np.uint8)
    label_atlas = np.zeros((atlas_h, atlas_w), np.uint8)
    crops: Iterable[FaceCrop] = layout.crops
    if progress:
        crops = progress_bar(crops, desc="render cube faces", unit="face", leave=False)
    flags = pyrender.RenderFlags
    try:
        for crop in crops:
            # pyrender's principal point counts from pixel edges: OpenCV centre + 0.5.
            gl_cam = pyrender.IntrinsicsCamera(
                fx=half, fy=half,
                cx=layout.centre_px + 0.5 - crop.x0, cy=layout.centre_px + 0.5 - crop.y0,
                znear=Z_NEAR_M, zfar=Z_FAR_M,
            )
            if cam_node is not None:
                pscene.remove_node(cam_node)
            cam_node = pscene.add(gl_cam, pose=_face_pose(camera, layout, crop))
            renderer.viewport_width, renderer.viewport_height = crop.width, crop.height
            if color:
                gl_scene.show(labels=False)
                lit, _ = renderer.render(pscene, flags=flags.FLAT | flags.SKIP_CULL_FACES)
                color_atlas[: crop.height, crop.atlas_x0:crop.atlas_x0 + crop.width] = lit[..., :3]
            gl_scene.show(labels=True)
            seg_img, _ = renderer.render(
                pscene, flags=flags.SEG | flags.SKIP_CULL_FACES, seg_node_map=gl_scene.seg
            )
            cols = slice(crop.atlas_x0, crop.atlas_x0 + crop.width)
            label_atlas[: crop.height, cols] = seg_img[..., 0]
    finally:
        renderer.delete()
    t2 = time.perf_counter()
    return FaceAtlas(color_atlas, label_atlas, gl_setup_s=t1 - t0, faces_s=t2 - t1)
