"""The public API of ``rvmsim``: every listed name resolves, the examples run, importing the
package starts no OpenGL, the lazy top level has its types, every name has one home, and the
surface changes only on purpose (a snapshot, ``tests/api_surface.txt``: after a deliberate
change, ``RVMSIM_UPDATE_API=1 pytest tests/test_api.py`` writes it anew, and the diff shows
the change in review)."""

from __future__ import annotations

import ast
import doctest
import importlib
import os
import pkgutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import rvmsim

REPO = Path(__file__).resolve().parents[1]
#: Every subpackage of rvmsim (but rvmsim.testing: what tests and benchmarks share, no API).
PACKAGES = tuple(sorted(m.name for m in pkgutil.iter_modules(rvmsim.__path__)
                        if m.ispkg and m.name != "testing"))
SURFACE = Path(__file__).with_name("api_surface.txt")


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


def _surface() -> list[str]:
    """``rvmsim: NAME`` and ``rvmsim.PACKAGE: NAME`` for every public name, sorted."""
    rows = [f"rvmsim: {n}" for n in rvmsim.__all__]
    for package in PACKAGES:
        rows += [f"rvmsim.{package}: {n}"
                 for n in importlib.import_module(f"rvmsim.{package}").__all__]
    return sorted(rows)


def test_the_public_surface_changes_only_on_purpose():
    now = _surface()
    if os.environ.get("RVMSIM_UPDATE_API"):
        SURFACE.write_text("\n".join(now) + "\n")
    recorded = SURFACE.read_text().splitlines()
    added, removed = sorted(set(now) - set(recorded)), sorted(set(recorded) - set(now))
    assert not added and not removed, (
        f"public names added {added}, removed {removed}; if deliberate, run "
        "RVMSIM_UPDATE_API=1 pytest tests/test_api.py and commit tests/api_surface.txt")


def test_every_public_name_has_one_home():
    homes: dict[str, list[str]] = {}
    for package in PACKAGES:
        for n in importlib.import_module(f"rvmsim.{package}").__all__:
            homes.setdefault(n, []).append(package)
    twice = {n: h for n, h in homes.items() if len(h) > 1}
    assert not twice, f"names exported by several subpackages: {twice}"


def test_the_stub_types_every_lazy_name_as_it_resolves():
    """``rvmsim/__init__.pyi`` imports each lazy name from the module ``_LAZY`` resolves it
    from, and nothing else: type checkers see what ``rvmsim.NAME`` returns."""
    stub = ast.parse((REPO / "rvmsim" / "__init__.pyi").read_text())
    typed = {}
    for node in stub.body:
        if isinstance(node, ast.ImportFrom):
            for a in node.names:
                typed[a.asname or a.name] = (f"rvmsim.{node.module}", a.name)
    lazy = {n: target for n, target in rvmsim._LAZY.items()}
    assert {n: typed[n] for n in lazy if n in typed} == lazy
    assert set(typed) - {"__version__"} == set(rvmsim.__all__)
