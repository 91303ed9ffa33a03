"""Small scenes for tests and benchmarks: a bundled vehicle on a fraction of its sensor.

Every test that wants a quick render builds its scene here, so every small scene is the
bundled one with the sensor resampled the way ``rvmsim render --scale`` resamples it
(:meth:`rvmsim.camera.FisheyeCamera.scaled`): the image size is rounded, focal lengths
scale with the side they belong to, the principal point scales about the pixel *edges*
(``(c + 0.5) · s − 0.5``), a pixel pitch by ``1 / s``; the skew (a ratio: ``u = f_x (x +
skew · y) + c_x``) stays, and ``K[0][1] = f_x · skew`` scales with ``s_x``; a field of view
across the width and a focal length in mm need nothing (they are not in pixels).  A fixed
cube face size (``render.face_size_px``) follows the sensor too.  So a scene point seen at
``(u, v)`` on the full sensor is at ``((u + 0.5) s_x − 0.5, (v + 0.5) s_y − 0.5)`` on the
small one, and ``load_small_scene(L, s).fisheye_camera()`` is the bundled camera
``.scaled(s)`` (whose skew agrees while ``s_x = s_y``, as for every bundled sensor).

Relative mesh paths are made absolute (the bundled scenes' folder), so the scene file can be
written into any folder.
"""

from __future__ import annotations

import copy
import functools
from pathlib import Path
from typing import Any, Final, Literal

import yaml

from rvmsim.scene import Scene, scene_from_dict

#: The source checkout these helpers serve (they read its bundled scenes).
ROOT: Final = Path(__file__).resolve().parents[2]
#: The bundled scenes' folder.
SCENES: Final = ROOT / "scenes"
#: The default fraction of the sensor: 1280 × 960 → 320 × 240 px.
QUARTER: Final = 0.25
#: ``variation=KEEP``: the bundled scene's own ``variation`` section stays.
KEEP: Final = "keep"
#: A scene key set to this is deleted by :func:`apply_edits`.
DELETE: Final = None

Variation = dict[str, Any] | None | Literal["keep"]


@functools.lru_cache(maxsize=None)
def _bundled_text(letter: str) -> str:
    return (SCENES / f"vehicle_{letter}.yaml").read_text()


def _round_px(value: float) -> int:
    return max(1, int(round(value)))


def scale_intrinsics(intr: dict[str, Any], sx: float, sy: float) -> dict[str, Any]:
    """The scene file's ``camera.intrinsics`` for a sensor resampled by ``sx`` × ``sy``.

    Parameters
    ----------
    intr : dict
        One of the four forms of :class:`rvmsim.scene.schema.Intrinsics` (fx/fy [cx/cy,
        skew]; K; horizontal_fov_deg; focal_length_mm + pixel_pitch_um).
    sx, sy : float
        New width / old width and new height / old height (dimensionless).

    Returns
    -------
    dict
        The same form, every pixel value scaled (px, px/rad, µm/px).
    """
    out = dict(intr)
    for key, s in (("fx", sx), ("fy", sy)):
        if key in out:
            out[key] = float(out[key]) * s
    for key, s in (("cx", sx), ("cy", sy)):
        if out.get(key) is not None:
            out[key] = (float(out[key]) + 0.5) * s - 0.5
    if out.get("K") is not None:  # u = fx·x + fx·skew·y + cx: the first row scales with u
        (fx, skew_fx, cx), (_, fy, cy), _ = out["K"]
        out["K"] = [[float(fx) * sx, float(skew_fx) * sx, (float(cx) + 0.5) * sx - 0.5],
                    [0.0, float(fy) * sy, (float(cy) + 0.5) * sy - 0.5],
                    [0.0, 0.0, 1.0]]
    if out.get("pixel_pitch_um") is not None:
        out["pixel_pitch_um"] = float(out["pixel_pitch_um"]) / sx
    return out


def _absolute_meshes(node: Any) -> None:
    """Every relative ``mesh:`` path below ``node`` made absolute (bundled scenes' folder)."""
    if isinstance(node, dict):
        mesh = node.get("mesh")
        if isinstance(mesh, str) and not Path(mesh).expanduser().is_absolute():
            node["mesh"] = str((SCENES / mesh).resolve())
        for value in node.values():
            _absolute_meshes(value)
    elif isinstance(node, list):
        for value in node:
            _absolute_meshes(value)


def apply_edits(doc: dict[str, Any], edit: dict[str, Any] | None) -> dict[str, Any]:
    """``doc`` with each dotted key of ``edit`` set to its value, in place (and returned).

    ``"camera.mount.pitch_deg": 30`` sets a nested key, creating missing mappings;
    ``"vehicle.extra.0.mesh"`` indexes a list; a value of :data:`DELETE` (None) deletes the
    key.
    """
    for key, value in (edit or {}).items():
        node: Any = doc
        *path, last = key.split(".")
        for part in path:
            node = node[int(part)] if isinstance(node, list) else node.setdefault(part, {})
        if value is DELETE:
            if isinstance(node, list):
                del node[int(last)]
            else:
                node.pop(last, None)
        elif isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return doc


def small_scene_doc(letter: str = "a", scale: float = QUARTER, *,
                    edit: dict[str, Any] | None = None,
                    variation: Variation = KEEP) -> dict[str, Any]:
    """Bundled vehicle ``letter`` on ``scale`` of its sensor, as a scene document.

    Parameters
    ----------
    letter : str
        The bundled vehicle (``scenes/vehicle_<letter>.yaml``).
    scale : float
        Fraction of the sensor (0.25: 1280 × 960 → 320 × 240 px).
    edit : dict, optional
        Dotted keys set afterwards (:func:`apply_edits`; they win over the scaling).
    variation : dict, None or KEEP
        The ``variation`` section: the bundled one (:data:`KEEP`), none (None) or this one.
    """
    doc: dict[str, Any] = yaml.safe_load(_bundled_text(letter))
    cam = doc["camera"]
    w, h = cam["image_size"]
    nw, nh = _round_px(w * scale), _round_px(h * scale)
    cam["image_size"] = [nw, nh]
    cam["intrinsics"] = scale_intrinsics(cam["intrinsics"], nw / w, nh / h)
    render = doc.get("render") or {}
    if render.get("face_size_px") is not None:
        render["face_size_px"] = max(16, _round_px(render["face_size_px"] * scale))
    _absolute_meshes(doc.get("vehicle"))
    if variation is None:
        doc.pop("variation", None)
    elif variation != KEEP:
        doc["variation"] = copy.deepcopy(variation)
    return apply_edits(doc, copy.deepcopy(edit))


def small_scene_text(letter: str = "a", scale: float = QUARTER, *,
                     edit: dict[str, Any] | None = None, variation: Variation = KEEP) -> str:
    """:func:`small_scene_doc` as YAML text."""
    text: str = yaml.safe_dump(small_scene_doc(letter, scale, edit=edit, variation=variation),
                               sort_keys=False)
    return text


def write_small_scene(folder: Path, letter: str = "a", scale: float = QUARTER, *,
                      name: str | None = None, edit: dict[str, Any] | None = None,
                      variation: Variation = KEEP) -> Path:
    """:func:`small_scene_doc` written to ``folder/name`` (default ``vehicle_<letter>.yaml``);
    returns the file's path."""
    path = folder / (name or f"vehicle_{letter}.yaml")
    path.write_text(small_scene_text(letter, scale, edit=edit, variation=variation))
    return path


def load_small_scene(letter: str = "a", scale: float = QUARTER, *,
                     edit: dict[str, Any] | None = None, variation: Variation = KEEP,
                     source: str | None = None) -> Scene:
    """:func:`small_scene_doc` as a :class:`~rvmsim.scene.Scene` (relative paths resolve
    against the bundled scenes' folder; ``source`` names it in messages)."""
    doc = small_scene_doc(letter, scale, edit=edit, variation=variation)
    return scene_from_dict(doc, base_dir=SCENES,
                           source=source or f"vehicle_{letter}_x{scale:g}.yaml")
