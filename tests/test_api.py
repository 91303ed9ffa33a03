"""The public API of ``rvmsim``: every listed name resolves, the examples run, and importing
the package starts no OpenGL."""

from __future__ import annotations

import doctest
import importlib
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import rvmsim

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("storage", "camera", "scene", "render", "isp", "criteria", "percar", "robust",
            "search", "runs", "tune", "batch", "validate", "eol", "report", "cli")


@pytest.mark.parametrize("name", rvmsim.__all__)
def test_every_public_name_resolves(name):
    assert getattr(rvmsim, name) is not None
    assert name in dir(rvmsim)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_thing"):
        rvmsim.no_such_thing  # noqa: B018


@pytest.mark.parametrize("package", PACKAGES)
def test_every_subpackage_lists_its_api(package):
    mod = importlib.import_module(f"rvmsim.{package}")
    assert mod.__all__, f"rvmsim.{package} has an empty __all__"
    missing = [n for n in mod.__all__ if not hasattr(mod, n)]
    assert not missing, f"rvmsim.{package}.__all__ names what it lacks: {missing}"
    assert len(set(mod.__all__)) == len(mod.__all__), f"rvmsim.{package}.__all__ repeats names"


def test_import_starts_no_opengl():
    code = ("import sys, rvmsim; rvmsim.load_scene; "
            "print(sorted(m for m in ('pyrender', 'OpenGL', 'trimesh', 'cv2') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pyrender" not in out.stdout and "OpenGL" not in out.stdout, out.stdout


def test_docstring_examples(tmp_path, monkeypatch):
    """The examples in ``rvmsim.__doc__`` (scene, render, ISP + ECs, a short run, its report,
    an error) run as written, from the repository folder."""
    monkeypatch.chdir(REPO)
    monkeypatch.setenv("RVMSIM_CACHE", str(tmp_path / "cache"))
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    globs = {"run_dir": tmp_path / "run"}
    tests = finder.find(rvmsim, "rvmsim", globs=globs)
    assert tests and tests[0].examples, "rvmsim's docstring has no examples"
    for t in tests:
        runner.run(t)
    res = runner.summarize(verbose=False)
    assert res.failed == 0 and res.attempted >= 10, res


def test_version_matches_the_package_metadata():
    """``rvmsim.__version__`` is what pyproject.toml declares (one version, two places)."""
    declared = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    assert rvmsim.__version__ == declared["project"]["version"]
