"""What the console writes: params files and setting reports, inside its folder only."""

from __future__ import annotations

import pytest

from rvmsim.console import evaluate_setting, open_session, save_params, write_setting_report
from rvmsim.errors import RvmsimError
from rvmsim.isp import load_params
from rvmsim.runs import rank_params_text


def test_a_saved_file_reads_back_as_the_setting(run_copy):
    s = open_session(run_copy / "run")
    frame = evaluate_setting(s, s.start)
    path = save_params(s, frame, "first")
    assert path.parent == (run_copy / "run" / "console").resolve()
    params, output = load_params(path)
    assert params == s.start and output == s.search_output
    # the body is what `rvmsim select --rank 1` writes for the same candidate
    select = rank_params_text(run_copy / "run", 1)
    assert path.read_text().split("\n", 1)[1] == select.split("\n", 1)[1]


def test_a_scene_session_writes_into_its_out_folder(small_run, tmp_path):
    s = open_session(small_run / "scene.yaml", out_root=tmp_path / "out")
    path = save_params(s, evaluate_setting(s, s.start))
    assert path.parent == (tmp_path / "out" / "scene" / "console").resolve()
    assert load_params(path)[0] == s.start


def test_a_console_folder_leading_outside_is_refused(run_copy, tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (run_copy / "run" / "console").symlink_to(outside)
    s = open_session(run_copy / "run")
    with pytest.raises(RvmsimError, match="outside"):
        save_params(s, evaluate_setting(s, s.start))
    assert list(outside.iterdir()) == []


def test_the_report_escapes_the_scene_strings(tmp_path):
    from rvmsim.testing.scenes import write_small_scene

    scene = write_small_scene(tmp_path, name="scene.yaml",
                              edit={"name": "<script>alert(1)</script>",
                                    "description": "a & <b>b</b>"})
    s = open_session(scene, out_root=tmp_path / "out")
    text = write_setting_report(s, s.start, "r").read_text()
    assert "<script>" not in text and "&lt;script&gt;alert(1)&lt;/script&gt;" in text
    assert "a &amp; &lt;b&gt;b&lt;/b&gt;" in text
    assert 'id="ec-table"' in text and 'id="params"' in text
