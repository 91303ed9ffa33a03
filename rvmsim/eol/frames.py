"""Fisheye frames of a scene from any camera pose, with the body at a load state.

:class:`PoseRenderer` renders one scene from many poses of one camera: the cube layout
depends only on the lens (it is made once), the meshes are built once, and each pose renders
the needed cube faces and folds them (:mod:`rvmsim.render`).  The station renders the
labels at each car's measured pose this way (:meth:`PoseRenderer.labels`: not cached, a pose
is seen once), and its nominal frame and synthetic captures through the render cache
(:meth:`PoseRenderer.frame`, keyed on the scene, pose and body pose).

Conventions
-----------
Images are (H, W) of the camera, pixel centres at integer coordinates; a body pose is a
(4, 4) rigid motion of the scene frame applied to the vehicle's parts
(:func:`rvmsim.robust.body_pose`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..camera import FisheyeCamera
from ..render import (CubeLayout, FaceCrop, FisheyeImages, cached_cube, cube_layout, fold,
                      fold_labels, posed_parts, render_faces)
from ..scene import Part, Scene, build_parts

__all__ = ["PoseRenderer", "restricted_layout"]


class PoseRenderer:
    """Renders ``scene`` from poses of ``camera`` (its lens and sensor; its own pose is not
    used), with the vehicle's parts at ``body_pose``.

    Parameters
    ----------
    scene : Scene
    camera : FisheyeCamera
        Lens, intrinsics and image size (px) of every frame.
    body_pose : (4, 4) float, optional
        Rigid motion of the vehicle's parts (None: as modelled).
    """

    def __init__(self, scene: Scene, camera: FisheyeCamera,
                 body_pose: np.ndarray | None = None):
        r = scene.render
        self.scene = scene
        self.camera = camera
        self.body_pose = body_pose
        self.layout: CubeLayout = cube_layout(camera, face_size=r.face_size_px,
                                              oversample=r.oversample,
                                              max_face_size=r.max_face_size_px)
        self._parts: list[Part] | None = None

    def parts(self) -> list[Part]:
        """The scene's meshes (built on first use), the vehicle's at the body pose, without
        textures (the label pass does not read them, and uploading one costs ~0.2 s)."""
        if self._parts is None:
            self._parts = [dataclasses.replace(p, texture=None) for p in
                           posed_parts(build_parts(self.scene), self.body_pose)]
        return self._parts

    def _at(self, pose: FisheyeCamera) -> FisheyeCamera:
        cam = self.camera
        return dataclasses.replace(cam, rotation=pose.rotation, position=pose.position)

    def frame(self, pose: FisheyeCamera, *, progress: bool = False) -> FisheyeImages:
        """Colour and labels from ``pose``'s position and rotation, through the render
        cache (:func:`rvmsim.render.cached_cube`)."""
        cam = self._at(pose)
        color, labels, _ = cached_cube(self.scene, cam, self.layout, body_pose=self.body_pose,
                                       parts=lambda: build_parts(self.scene), progress=progress)
        assert color is not None  # asked for
        c, lab = fold(self.layout, color, labels, self.scene.render.color_filter)
        return FisheyeImages(color=c, labels=lab, camera=cam, face_size=self.layout.face_size,
                             scene=self.scene)

    def labels(self, pose: FisheyeCamera, pixels: np.ndarray | None = None) -> np.ndarray:
        """Only the label image ((H, W) uint8) from ``pose``'s position and rotation,
        rendered now (not cached).

        Parameters
        ----------
        pose : FisheyeCamera
            Its position and rotation place the cube.
        pixels : (H, W) bool, optional
            Render only these fisheye pixels (the others are ``VOID``): each face only
            over the rectangle they need (:func:`restricted_layout`), at the same face size,
            so their labels are the whole render's.
        """
        cam = self._at(pose)
        layout = self.layout if pixels is None else restricted_layout(self.layout, pixels)
        atlas = render_faces(self.parts(), layout, cam, sky=self.scene.render.sky_color,
                             color=False)
        return fold_labels(layout, atlas.labels)


def restricted_layout(layout: CubeLayout, pixels: np.ndarray) -> CubeLayout:
    """``layout`` for only some of its fisheye pixels: each face's crop shrunk to the
    rectangle those pixels sample (plus a pixel's guard), at the same face size and face
    pixel grid, so every kept pixel samples the same face pixel as before; the other
    pixels are outside the field (``VOID`` when folded).

    Parameters
    ----------
    layout : CubeLayout
    pixels : (H, W) bool
        The fisheye pixels to keep.
    """
    keep = np.asarray(pixels, dtype=bool) & layout.in_fov
    atlas_x = np.full(keep.shape, -1.0, np.float32)
    atlas_y = np.full(keep.shape, -1.0, np.float32)
    crops: list[FaceCrop] = []
    offset = 0
    for c in layout.crops:
        sel = keep & (layout.atlas_x >= c.atlas_x0) & (layout.atlas_x < c.atlas_x0 + c.width)
        if not sel.any():
            continue
        fx = layout.atlas_x[sel] - c.atlas_x0 + c.x0  # face pixel grid
        fy = layout.atlas_y[sel] + c.y0
        x0 = max(int(np.floor(fx.min())) - 1, c.x0)
        x1 = min(int(np.ceil(fx.max())) + 2, c.x0 + c.width)
        y0 = max(int(np.floor(fy.min())) - 1, c.y0)
        y1 = min(int(np.ceil(fy.max())) + 2, c.y0 + c.height)
        crops.append(FaceCrop(c.face, x0, y0, x1 - x0, y1 - y0, offset))
        atlas_x[sel] = fx - x0 + offset
        atlas_y[sel] = fy - y0
        offset += x1 - x0
    if not crops:
        raise ValueError("none of the pixels to keep is inside the lens's field")
    return CubeLayout(layout.face_size, tuple(crops), atlas_x, atlas_y, keep,
                      layout.cube_rotation)
