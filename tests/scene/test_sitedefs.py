"""Site definitions (rvmsim/scene/sitedefs.py): bundled sites, placement by the vehicle's
width, the FMVSS site's values, render keys, and the objects of a rendered site standing
where the camera model projects them."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import cv2
import numpy as np
import pytest
import trimesh
import yaml

from rvmsim import labels as L
from rvmsim.render import render_fisheye, scene_key
from rvmsim.scene import fmvss111
from rvmsim.scene.placement import scene_site, scene_sites, scene_vehicle_width, site_scene
from rvmsim.scene.sitedefs import BUNDLED_SITES, SiteError, bundled_site, load_site, place_objects

from rvmsim.testing.scenes import SCENES, load_small_scene, small_scene_doc

FT, INCH = 0.3048, 0.0254
#: The bundled regulations' folder, read as files (independently of the loader).
REGULATIONS = Path(__file__).resolve().parents[2] / "rvmsim" / "regulations"


# ---------------------------------------------------------------------------- loading
@pytest.mark.parametrize("name", sorted(BUNDLED_SITES))
def test_every_bundled_site_loads_with_its_rows_as_written(name):
    site = bundled_site(name)
    # the file itself, read independently of the loader
    raw = yaml.safe_load((REGULATIONS / name / "site.yaml").read_text(encoding="utf-8"))
    assert site.name == raw["name"] == name
    assert [r.name for r in site.rows] == [r["name"] for r in raw["rows"]]
    objects = place_objects(site, 1.8)
    assert len(objects) == sum(len(r["x"]) for r in raw["rows"])
    assert [o.index for o in objects] == list(range(len(objects)))
    labels = [k for o in objects for k in o.labels]
    assert len(set(labels)) == len(labels) and min(labels) >= L.SITE_OBJECT_BASE


def _site_file(tmp_path: Path, text: str, name: str = "site.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


SITE = """\
name: probe
position_reference: {ref}
rows:
  - name: near
    z: 0.5
    x: [-0.7, {{of_width: 0.5, m: 0.1}}, {{of_width: -0.25}}]
    diameter: 0.4
    height: 0.9
    marking: {{top_band: 0.2}}
  - name: far
    names: [left, right]
    z: 2.0
    x: [{{of_width: -0.5, m: -0.2}}, 1.1]
    diameter: 0.2
    height: 0.6
"""


@pytest.mark.parametrize("ref", ["centre", "surface"])
def test_place_objects_uses_of_width_times_width_plus_m_and_the_reference(tmp_path, ref):
    site = load_site(_site_file(tmp_path, SITE.format(ref=ref)))
    width = 1.73
    objs = {o.name: o for o in place_objects(site, width)}
    shift = {"centre": 0.0, "surface": 1.0}[ref]  # × the radius
    expected = {"near.1": (-0.7, 0.5 + shift * 0.2), "near.2": (0.5 * width + 0.1, 0.5 + shift * 0.2),
                "near.3": (-0.25 * width, 0.5 + shift * 0.2),
                "left": (-0.5 * width - 0.2, 2.0 + shift * 0.1), "right": (1.1, 2.0 + shift * 0.1)}
    assert sorted(objs) == sorted(expected)
    for name, (x, z) in expected.items():
        assert (objs[name].x, objs[name].z) == pytest.approx((x, z), abs=1e-12)
    assert objs["near.2"].top_band == 0.2 and objs["left"].top_band == 0.0
    assert objs["right"].row == "far" and objs["right"].radius == pytest.approx(0.1)


def _row1_x(scene) -> list[float]:
    at = site_scene(scene, "unr158")
    return [o.x for o in at.test_site.site_objects if o.row == "row1"]


def test_the_vehicle_width_given_wins():
    scene = load_small_scene("a", edit={"vehicle.width": 2.4})
    assert scene_vehicle_width(scene) == 2.4
    assert _row1_x(scene) == pytest.approx([-1.2, 0.0, 1.2])


def test_without_a_width_the_widest_block_part_places_the_objects():
    doc = small_scene_doc("a")
    widest = max(doc["vehicle"][p]["width"] for p in ("bumper", "garnish", "trunk"))
    scene = load_small_scene("a")
    assert scene_vehicle_width(scene) == widest
    assert _row1_x(scene) == pytest.approx([-widest / 2, 0.0, widest / 2])
    # a narrower bumper: the trunk (if now widest) places them
    narrow = load_small_scene("a", edit={"vehicle.bumper.width": 1.2})
    expected = max(1.2, doc["vehicle"]["garnish"]["width"], doc["vehicle"]["trunk"]["width"])
    assert scene_vehicle_width(narrow) == expected


def test_a_mesh_part_is_measured_by_its_x_extent():
    doc = small_scene_doc("f")
    bumper = doc["vehicle"]["bumper"]
    mesh = trimesh.load(bumper["mesh"], force="mesh")
    scale = {"mm": 1e-3, "m": 1.0}[bumper.get("units", "m")]
    mesh_width = float(np.ptp(mesh.vertices[:, 0])) * scale
    blocks = [doc["vehicle"][p]["width"] for p in ("garnish", "trunk")]
    assert mesh_width > max(blocks)  # the car's width is its (mesh) bumper's
    scene = load_small_scene("f")
    assert scene_vehicle_width(scene) == pytest.approx(mesh_width, abs=1e-9)
    assert _row1_x(scene) == pytest.approx([-mesh_width / 2, 0.0, mesh_width / 2], abs=1e-9)


# ---------------------------------------------------------------------------- FMVSS site
def test_the_fmvss_site_file_holds_the_fmvss111_constants():
    raw = yaml.safe_load((REGULATIONS / "fmvss111" / "site.yaml").read_text(encoding="utf-8"))
    rows = {r["name"]: r for r in raw["rows"]}
    for row in rows.values():
        assert row["diameter"] == fmvss111.OBJECT_DIAMETER_M
        assert row["height"] == fmvss111.OBJECT_HEIGHT_M
        for name, x in zip(row["names"], row["x"]):
            assert fmvss111.OBJECT_POSITIONS_M[name] == (x, row["z"])
    assert sorted(fmvss111.OBJECT_POSITIONS_M) == list("ABCDEFG")
    assert rows["far"]["marking"]["top_band"] == fmvss111.STRIPE_WIDTH_M
    assert rows["near"]["marking"]["lower_patch"] == fmvss111.LOWER_PATCH_HEIGHT_M
    assert raw["position_reference"] == fmvss111.OBJECT_POSITION_REFERENCE
    # and the regulation's imperial figures, converted here (within the file's rounding)
    assert fmvss111.OBJECT_DIAMETER_M == pytest.approx(12 * INCH, abs=0.006)
    assert fmvss111.OBJECT_HEIGHT_M == pytest.approx(32 * INCH, abs=0.015)
    assert fmvss111.STRIPE_WIDTH_M == pytest.approx(6 * INCH, abs=0.003)
    for name, (x, z) in fmvss111.OBJECT_POSITIONS_M.items():
        assert z == pytest.approx({"ABC": 20, "DE": 10, "FG": 1}[
            next(k for k in ("ABC", "DE", "FG") if name in k)] * FT, abs=0.005)
        assert abs(x) == pytest.approx(0.0 if name == "B" else 5 * FT, abs=0.005)


def test_the_default_scene_keeps_its_render_key():
    plain = load_small_scene("a")
    explicit = load_small_scene("a", edit={"sites": ["fmvss111"]})
    more = load_small_scene("a", edit={"sites": ["fmvss111", "unr158", "jp"],
                                       "vehicle.width": 2.2})
    assert scene_key(plain) == scene_key(explicit) == scene_key(more)
    assert site_scene(explicit, "fmvss111") is explicit
    keys = {scene_key(site_scene(plain, s)) for s in ("unr158", "jp")}
    assert len(keys) == 2 and scene_key(plain) not in keys
    # the objects' placement is in a site scene's key (vehicle.width moves them)
    assert scene_key(site_scene(more, "unr158")) != scene_key(site_scene(plain, "unr158"))


def test_a_site_scene_has_none_of_the_fmvss_site():
    scene = load_small_scene("a")
    at = site_scene(scene, "unr158")
    ts = at.test_site
    assert ts.site == "unr158" and not ts.fmvss and not ts.board.enabled
    assert not ts.ground_patterns
    assert all(ts.object_centre(c) is None for c in L.OBJECT_LETTERS)
    assert [o.name for o in ts.site_objects] == [f"row{r}.{i}" for r in (1, 2, 3)
                                                  for i in (1, 2, 3)]
    labels = _render(scene.model_dump_json(), "unr158").labels
    present = set(np.unique(labels).tolist())
    fmvss = {L.BOARD, L.GROUND_PATTERN, L.GUIDE_SIDE_NEG_X, L.GUIDE_SIDE_POS_X}
    fmvss |= {L.object_body(c) for c in L.OBJECT_LETTERS}
    fmvss |= {L.object_stripe(c) for c in L.OBJECT_LETTERS}
    fmvss |= {L.guide_cross(n) for n in range(1, L.MAX_CROSS_LINES + 1)}
    assert not present & fmvss
    assert any(k >= L.SITE_OBJECT_BASE for k in present)


# ---------------------------------------------------------------------------- rendered site
@functools.lru_cache(maxsize=None)
def _render(_key: str, site: str):
    return render_fisheye(site_scene(load_small_scene("a"), site))


def _tangent_points(cam_xz, obj, y):
    """The two points where lines of sight from the camera (plan view) touch the cylinder,
    at height ``y`` (scene frame, y down)."""
    ex, ez = cam_xz[0] - obj.x, cam_xz[1] - obj.z
    d = math.hypot(ex, ez)
    base, alpha = math.atan2(ex, ez), math.acos(obj.radius / d)
    return [[obj.x + obj.radius * math.sin(base + s * alpha), y,
             obj.z + obj.radius * math.cos(base + s * alpha)] for s in (-1, 1)]


def _nearest(mask: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Distance (px) from each point (N, 2) to the nearest true pixel centre of ``mask``."""
    vv, uu = np.nonzero(mask)
    pix = np.stack([uu, vv], 1).astype(float)
    return np.array([np.min(np.hypot(*(pix - p).T)) for p in uv])


def test_site_objects_render_where_the_camera_projects_them():
    scene = load_small_scene("a")
    at = site_scene(scene, "unr158")
    images = _render(scene.model_dump_json(), "unr158")
    cam, labels = images.camera, images.labels
    pos = cam.position
    assert -pos[1] > 0.8  # the camera looks down on every top
    checked = 0
    for obj in at.test_site.site_objects:
        body, band, top = obj.labels
        own = np.isin(labels, obj.labels)
        edge = own & ~cv2.erode(own.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
        # the top centre shows the top face; the point of the side nearest the camera (in
        # plan view) the band at the band's height and the body below it
        ex, ez = pos[0] - obj.x, pos[2] - obj.z
        fx, fz = np.array([obj.x, obj.z]) + obj.radius * np.array([ex, ez]) / math.hypot(ex, ez)
        band_mid = obj.height - (obj.top_band / 2 if obj.top_band else 0.075)
        pts = np.array([[obj.x, -obj.height, obj.z], [fx, -band_mid, fz],
                        [fx, -(obj.height - obj.top_band - 0.1), fz]])
        uv, ok = cam.project(pts)
        assert ok.all()
        # a top face seen edge-on (under 2 px between its near and far rim) may not raster
        rim, _ = cam.project(np.array([[fx, -obj.height, fz],
                                       [2 * obj.x - fx, -obj.height, 2 * obj.z - fz]]))
        top_ok = abs(rim[1, 1] - rim[0, 1]) >= 2.0
        wants = ((top,) if top_ok else obj.labels, (band if obj.top_band else body,), (body,))
        for (u, v), want in zip(uv, wants):
            if not (0 <= u < cam.width and 0 <= v < cam.height):
                continue
            seen = labels[int(round(v)), int(round(u))]
            if seen in L.BODY_LABELS:
                continue  # behind the bumper
            near = _nearest(np.isin(labels, want), np.array([[u, v]]))[0]
            assert near <= 1.5, (obj.name, want, near)
            checked += 1
        # the silhouette's side edges at the band's height
        y = -band_mid
        tuv, ok = cam.project(np.array(_tangent_points((pos[0], pos[2]), obj, y)))
        inside = ok & (tuv[:, 0] >= 1) & (tuv[:, 0] < cam.width - 1) & (tuv[:, 1] >= 1) \
            & (tuv[:, 1] < cam.height - 1)
        if inside.any():
            d = _nearest(edge, tuv[inside])
            assert d.max() <= 1.5, (obj.name, d)
            checked += int(inside.sum())
    assert checked >= 30


# ---------------------------------------------------------------------------- bad files
GOOD_ROW = "{name: r, z: 1, x: [0], diameter: 0.3, height: 0.8}"
BAD = {
    "malformed YAML": ("name: x\nrows: [\n", "malformed YAML"),
    "unknown key": (f"name: x\nbogus: 1\nrows: [{GOOD_ROW}]\n", "bogus"),
    "negative diameter": ("name: x\nrows:\n  - {name: r, z: 1, x: [0], diameter: -0.3, "
                          "height: 0.8}\n", "rows.0.diameter"),
    "top band too high": ("name: x\nrows:\n  - {name: r, z: 1, x: [0], diameter: 0.3, "
                          "height: 0.8, marking: {top_band: 0.8}}\n", "top_band"),
    "duplicate rows": (f"name: x\nrows: [{GOOD_ROW}, {GOOD_ROW}]\n", "rows"),
    "too many objects": ("name: x\nrows:\n" + "".join(
        f"  - {{name: r{k}, z: {k + 1}, x: [0, 1, 2, 3, 4, 5, 6, 7, 8], diameter: 0.3, "
        f"height: 0.8}}\n" for k in range(2)) + f"  - {GOOD_ROW}\n", "rows"),
    "bad name": (f"name: 'a b'\nrows: [{GOOD_ROW}]\n", "name"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_a_bad_site_file_is_one_line_naming_file_and_key(tmp_path, case):
    text, key = BAD[case]
    path = _site_file(tmp_path, text)
    with pytest.raises(SiteError) as err:
        load_site(path)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(str(path)) and key in message


def test_a_missing_site_file_named_by_a_scene_names_the_scene_and_key(tmp_path):
    """The scene loader checks every site the scene names, before anything renders."""
    from rvmsim.errors import SceneError

    with pytest.raises(SceneError) as err:
        load_small_scene("a", edit={"sites": ["fmvss111", "nosuch.yaml"]},
                         source=str(tmp_path / "car.yaml"))
    message = str(err.value)
    assert "\n" not in message and str(tmp_path / "car.yaml") in message
    assert "sites.1" in message and str(SCENES / "nosuch.yaml") in message
    with pytest.raises(SceneError, match=r"sites\.0: unknown site 'unr185'"):
        load_small_scene("a", edit={"sites": ["unr185"]})
    with pytest.raises(SceneError, match=r"sites\.1: site 'unr158' is named twice"):
        load_small_scene("a", edit={"sites": ["unr158", "unr158"]})


def test_a_site_file_named_by_a_scene_replaces_the_bundled_one(tmp_path):
    _site_file(tmp_path, SITE.format(ref="centre").replace("name: probe", "name: unr158"),
               "mine.yaml")
    doc = small_scene_doc("a", edit={"sites": ["mine.yaml"]})
    from rvmsim.scene import scene_from_dict

    scene = scene_from_dict(doc, base_dir=tmp_path, source=str(tmp_path / "car.yaml"))
    assert [s.name for s in scene_sites(scene)] == ["unr158"]
    at = site_scene(scene, "unr158")
    assert [o.name for o in at.test_site.site_objects][-2:] == ["left", "right"]
