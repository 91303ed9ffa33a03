"""The scene's eol section (rvmsim.scene.eol) and the station scene (rvmsim.scene.station)."""

from __future__ import annotations

import pytest
import yaml

from rvmsim.errors import SceneError
from rvmsim.render import scene_key
from rvmsim.scene import load_scene, scene_from_dict, station_scene, station_target

from rvmsim.testing.scenes import SCENES, small_scene_doc

MAT = {"name": "station mat", "origin": [-3.0, 0.3], "square_size": 0.3,
       "checker": [[0, 0, 6, 2.4]]}


def _scene(eol, edit=None):
    doc = small_scene_doc("a", edit={"eol": eol, **(edit or {})})
    return scene_from_dict(doc, base_dir=SCENES, source="s.yaml",
                           text=yaml.safe_dump(doc, sort_keys=False))


def test_the_station_has_only_its_own_target():
    sc = _scene({"target": "station mat", "ground_patterns": [MAT],
                 "pose": {"origin": [-3.0, 0.5], "yaw_deg": 2.0}})
    st = station_scene(sc)
    site = st.test_site
    assert not site.fmvss and not st.guidelines_shown and site.object_centre("A") is None
    assert not site.board.enabled
    assert [p.name for p in site.ground_patterns] == ["station mat"]
    assert site.ground_patterns[0].origin == (-3.0, 0.5) and site.ground_patterns[0].yaw_deg == 2
    # The scene itself (the ECs' test site) is untouched: no mat, the FMVSS site, the board.
    assert sc.test_site.ground_patterns == [] and sc.test_site.fmvss
    assert sc.test_site.board.enabled
    assert st.camera == sc.camera and st.vehicle == sc.vehicle


def test_the_eol_section_is_not_part_of_the_render_key():
    plain = scene_from_dict(small_scene_doc("a"), base_dir=SCENES)
    assert scene_key(_scene({"target": "board"})) == scene_key(plain)


def test_a_board_target_is_the_stations_board_or_the_sites_moved():
    sc = _scene({"target": "board", "pose": {"placement": "upright",
                                             "position": [0.0, -0.6, 1.2]}})
    board = station_target(sc)
    assert board.placement == "upright" and board.position == (0.0, -0.6, 1.2)
    assert board.squares == (8, 12)  # vehicle A's board
    own = _scene({"target": "board", "board": {"squares": [7, 10], "square_size": 0.1,
                                              "pattern": "charuco", "marker_size": 0.075,
                                              "placement": "upright",
                                              "position": [0, -0.7, 1.5]}},
                 edit={"test_site.board.enabled": False})
    st = station_scene(own)
    assert st.test_site.board.enabled and st.test_site.board.pattern == "charuco"
    assert not own.test_site.board.enabled  # the site keeps its own (none here)


def test_a_site_pattern_can_be_the_target():
    sc = load_scene(SCENES / "real" / "baic_eu5_rear.yaml")
    assert sc.eol is not None and sc.eol.target == "calibration mat"
    assert station_target(sc) == sc.test_site.ground_patterns[0]


@pytest.mark.parametrize("eol, where", [
    ({"target": "nope"}, "eol.target: 'nope' is neither 'board' nor the name of a ground "
                         "pattern (the scene has none)"),
    ({"target": "board", "pose": {"origin": [0, 1]}}, "eol.pose: origin cannot place a board"),
    ({"target": "station mat", "ground_patterns": [MAT], "pose": {"roll_deg": 1}},
     "eol.pose: roll_deg cannot place a ground pattern (its keys: origin, yaw_deg)"),
    ({"target": "board", "pose": {"roll_deg": 3}},
     "eol.pose: the board at this pose is invalid: pitch_deg and roll_deg need placement: free"),
    ({"target": "station mat", "ground_patterns": [MAT], "board": {"squares": [4, 4]}},
     "eol.board: the station's board is given but the target is 'station mat'"),
    ({"target": "station mat", "ground_patterns": [MAT, MAT]}, "eol.target: 'station mat' "
                                                                "names 2 ground patterns"),
    ({"target": ""}, "eol.target: String should have at least 1 character"),
    ({"target": "board", "height": 3}, "eol.height: unknown key"),
    ({"pose": {}}, "eol.target: missing required key"),
])
def test_a_bad_eol_section_names_its_key(eol, where):
    with pytest.raises(SceneError) as err:
        _scene(eol)
    assert f"s.yaml:" in str(err.value) and where in str(err.value), str(err.value)


def test_a_scene_without_an_eol_section_has_no_station():
    sc = scene_from_dict(small_scene_doc("a"), base_dir=SCENES, source="s.yaml")
    with pytest.raises(SceneError, match="s.yaml: eol: the scene has no eol section"):
        station_scene(sc)
