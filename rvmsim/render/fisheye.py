"""Render the rear-view camera's fisheye image (colour + labels) with pyrender off-screen.

Method
------
1. Every fisheye pixel centre is back-projected to a ray in the camera frame and assigned to
   a face of a cube centred at the camera; only the faces (and the part of each) that some
   ray hits are rendered (:mod:`rvmsim.render.cube`).
2. Each needed face is rendered twice by pyrender as a 90° pinhole view with a 2 px guard
   band (so bilinear sampling never reads past a face's edge): a lit colour pass and a
   segmentation pass (:mod:`rvmsim.render.gl`).
3. The faces are folded into the fisheye image: colour bilinearly, labels by nearest sampling
   of the same coordinates (IDs are never blended) (:mod:`rvmsim.render.fold`).

Conventions
-----------
Pixel centres at integer coordinates (OpenCV).  Fisheye pixels outside the lens's field are
labelled ``VOID`` and black; inside it, pixels where no geometry is hit are ``SKY``.
The headless GL platform is EGL unless ``PYOPENGL_PLATFORM`` says otherwise (``osmesa``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from .._io import image_size_problem
from ..camera import FisheyeCamera
from ..errors import SceneError
from ..scene import Scene, build_parts
from .cube import FACE_NAMES, cube_layout
from .fold import fold
from .gl import prepare_render, render_faces

__all__ = ["FisheyeImages", "render_fisheye"]


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
    scene : Scene, optional
        The scene rendered (ECs that need its geometry read it; None when unknown).
    """

    color: np.ndarray
    labels: np.ndarray
    camera: FisheyeCamera
    timings: dict[str, float] = field(default_factory=dict)
    face_size: int = 0
    faces: tuple[str, ...] = ()
    scene: Scene | None = None


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
        Turn the cube about the camera: the faces' seams move, the image must not (how the
        fold is checked seam-free; default: the cube aligned with the camera).
    progress : bool
        Show a progress bar over the cube faces.

    Returns
    -------
    FisheyeImages

    Raises
    ------
    SceneError
        When a mesh file of the scene cannot be loaded, or the camera's image is over the
        image size limit (:func:`rvmsim._io.image_size_problem`).

    Convention
    ----------
    Images are (H, W) of the camera, pixel centres at integer coordinates.
    """
    t0 = time.perf_counter()
    cam = scene.fisheye_camera() if camera is None else camera
    too_big = image_size_problem(cam.width, cam.height)  # a camera scaled up, or from the API
    if too_big is not None:
        raise SceneError(scene.source, "camera.image_size", f"cannot render: {too_big}")
    prepare_render()
    parts = build_parts(scene)
    layout = cube_layout(
        cam,
        face_size=face_size or scene.render.face_size_px,
        oversample=scene.render.oversample,
        max_face_size=scene.render.max_face_size_px,
        cube_rotation=cube_rotation,
    )
    t1 = time.perf_counter()
    atlas = render_faces(parts, layout, cam, sky=scene.render.sky_color, progress=progress)
    t3 = time.perf_counter()
    color, labels = fold(layout, atlas.color, atlas.labels, scene.render.color_filter)
    t4 = time.perf_counter()
    return FisheyeImages(
        color=color,
        labels=labels,
        camera=cam,
        timings={"meshes": t1 - t0, "gl_setup": atlas.gl_setup_s, "faces": atlas.faces_s,
                 "fold": t4 - t3},
        face_size=layout.face_size,
        faces=tuple(FACE_NAMES[f] for f in layout.faces),
        scene=scene,
    )
