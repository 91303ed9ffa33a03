"""The harness itself: it passes a clean failure and catches every way of not being one."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE, write_small_scene
from .harness import Case, Outcome, assert_clean_failure, check_case, run_rvmsim


def test_the_small_scene_is_valid(tmp_path):
    write_small_scene(tmp_path)
    out = run_rvmsim(["render", SMALL_SCENE, "--out", "r", "--no-progress"], cwd=tmp_path)
    assert out.code == 0, out.stderr
    assert "320x240" in out.stdout


def test_a_clean_failure_passes(case_dir):
    case = Case("missing-key", ("render", SMALL_SCENE, "--out", "r"), (SMALL_SCENE, "camera"),
                setup=lambda d: write_small_scene(d, {"camera": None}), keep=("run",))
    check_case(case, case_dir)


@pytest.mark.parametrize("out, why", [
    (Outcome(1, "", "rvmsim: error: x.yaml: k: bad\n"), "exit"),
    (Outcome(2, "", "rvmsim: error: x.yaml: k: bad\nmore\n"), "lines"),
    (Outcome(2, "", "Traceback (most recent call last):\n"), "Traceback"),
    (Outcome(2, "", "rvmsim: error: x.yaml: bad\n"), "not named"),
])
def test_unclean_failures_are_caught(out, why):
    with pytest.raises(AssertionError, match=why):
        assert_clean_failure(out, ["x.yaml", "k:"])


def test_a_changed_run_folder_is_caught(case_dir, monkeypatch):
    """A command that fails cleanly but touched a stored run fails the case."""
    from . import harness

    def spoiling_run(args, *, cwd, env=None, timeout_s=0.0):
        (cwd / "run" / "run.sqlite").write_bytes(b"")
        return Outcome(2, "", "rvmsim: error: scene.yaml: camera: missing required key\n")

    monkeypatch.setattr(harness, "run_rvmsim", spoiling_run)
    with pytest.raises(AssertionError, match="run changed"):
        check_case(Case("spoils", ("render",), (SMALL_SCENE,), keep=("run",)), case_dir)
