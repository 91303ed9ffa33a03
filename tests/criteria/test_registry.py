"""The EC registry: the built-ins are a plugin like any other; plugins load from modules and
files, pickle by reference, and an EC that breaks the API is refused in one line."""

from __future__ import annotations

import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rvmsim import criteria as C
from rvmsim.pipeline import CandidateEvaluator
from rvmsim.criteria import (
    BUILTIN_PLUGIN,
    EC_IDS,
    EcDefinition,
    LabelGroup,
    builtin_ecs,
    load_plugin,
    resolve_plugin,
)
from rvmsim.criteria.builtin import BOARD
from rvmsim.errors import CriteriaError

from . import ec_plugin_example

EXAMPLE = Path(ec_plugin_example.__file__)
ROOT = Path(__file__).resolve().parents[2]


def test_builtins_are_the_papers_eleven_from_their_plugin():
    ecs = builtin_ecs()
    assert tuple(ec.id for ec in ecs) == EC_IDS
    assert all(ec.plugin == BUILTIN_PLUGIN for ec in ecs)
    assert C.EC_DEFINITIONS == ecs
    assert C.GROUPS["board"] == BOARD.labels
    # binary ECs have no sigmoid, the others a default range and sigmoid
    for ec in ecs:
        assert (ec.default_sigmoid is None) == ec.binary == (ec.id in ("1-1", "2-4"))
        assert ec.default_range != (None, None)


def test_module_and_file_plugins_load_the_same_ecs(tmp_path):
    by_module = load_plugin("tests.criteria.ec_plugin_example")
    assert [ec.id for ec in by_module] == ["acme-board-centred"]
    assert by_module[0].plugin == "tests.criteria.ec_plugin_example"
    assert load_plugin("tests.criteria.ec_plugin_example") is by_module  # once per process
    shutil.copy(EXAMPLE, tmp_path / "mine.py")
    source = resolve_plugin("mine.py", tmp_path)
    assert source == str((tmp_path / "mine.py").resolve())
    by_file = load_plugin(source)
    assert by_file[0].plugin == source and by_file[0].id == by_module[0].id
    assert by_file[0].measure is not by_module[0].measure  # the file's own module
    assert resolve_plugin("acme_rvm.criteria", tmp_path) == "acme_rvm.criteria"


def test_ecs_pickle_by_reference_to_their_plugin(tmp_path):
    shutil.copy(EXAMPLE, tmp_path / "by_path.py")
    (ec,) = load_plugin(str(tmp_path / "by_path.py"))
    data = pickle.dumps(ec)
    assert b"by_path.py" in data and b"board_centre_offset" not in data  # no functions
    assert pickle.loads(data) is ec
    # A fresh process has never loaded the file: unpickling loads it and measures with it.
    code = ("import pickle, sys, numpy as np\n"
            "from rvmsim import labels as L\n"
            "from rvmsim.criteria import measure\n"
            "ec = pickle.loads(sys.stdin.buffer.read())\n"
            "img = np.full((20, 40), L.GROUND, np.uint8); img[5:9, 2:8] = L.BOARD\n"
            "print(ec.id, measure(img, ecs=[ec]).values[ec.id])\n")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    res = subprocess.run([sys.executable, "-c", code], input=data, capture_output=True,
                         env=env, cwd=tmp_path, timeout=120)
    assert res.returncode == 0, res.stderr.decode()
    # board centre x = 4.5, image centre 19.5: 15 px of 40
    assert res.stdout.decode().split() == ["acme-board-centred", str(100 * 15 / 40)]


def test_criteria_and_evaluator_pickle_with_plugin_ecs(tmp_path):
    shutil.copy(EXAMPLE, tmp_path / "ec.py")
    crit = tmp_path / "c.yaml"
    crit.write_text("plugins: [ec.py]\necs: [4-1, acme-board-centred]\n")
    c = C.load_criteria(crit)
    again = pickle.loads(pickle.dumps(c))
    assert again.ids == c.ids == ("4-1", "acme-board-centred")
    assert again.ecs[1] is c.ecs[1]
    labels = np.full((30, 60), 2, np.uint8)
    labels[10:20, 40:50] = BOARD.labels[0]
    ev = CandidateEvaluator(labels, criteria=c)
    assert pickle.loads(pickle.dumps(ev)).criteria.ids == c.ids


def _bad(name: str, body: str) -> str:
    head = ("from rvmsim import labels as L\n"
            "from rvmsim.criteria import EcDefinition, LabelGroup, Measurement\n"
            "G = LabelGroup('board', (L.BOARD,))\n"
            "def ok(src, options):\n    return Measurement(1.0)\n")
    return head + body


@pytest.mark.parametrize("body, words", [
    ("import no_such_module_for_rvmsim\n", "failed on import (ModuleNotFoundError"),
    ("def broken(:\n", "failed on import (SyntaxError"),
    ("X = 1\n", "needs a module-level ECS"),
    ("ECS = ['1-1']\n", "must be an rvmsim.criteria.EcDefinition"),
    ("ECS = [EcDefinition('x', 'x', '', ('board',), ok)]\n", "groups must be a tuple of LabelGroup"),
    ("ECS = [EcDefinition('x y', 'x', '', (G,), ok)]\n", "without spaces"),
    ("ECS = [EcDefinition('x', 'x', '', (G,), ok, default_range=(5, 1))]\n", "low <= high"),
    ("ECS = [EcDefinition('x', 'x', '', (G,), ok), EcDefinition('x', 'y', '', (G,), ok)]\n",
     "two ECs have the same id"),
    ("ECS = [EcDefinition('x', 'x', '', (G,), lambda s, o: 'tall')]\n", "x: measure returned str"),
    ("ECS = [EcDefinition('x', 'x', '', (G,), lambda s, o: 1 / 0)]\n",
     "x: the EC fails on an empty 8x8 image (ZeroDivisionError"),
    ("ECS = [EcDefinition('x', 'x', '', (), lambda s, o: Measurement(s.window(G)[0]))]\n",
     "not declared by the ECs measured"),
    ("ECS = [EcDefinition('1-1', 'mine', '', (G,), ok)]\n", "EC '1-1', which rvmsim.criteria.builtin"),
])
def test_plugin_that_breaks_the_api_is_one_line(tmp_path, body, words):
    plugin = tmp_path / "bad_plugin.py"
    plugin.write_text(_bad("bad", body))
    crit = tmp_path / "c.yaml"
    crit.write_text("name: x\nplugins:\n  - bad_plugin.py\n")
    with pytest.raises(CriteriaError) as info:
        C.load_criteria(crit)
    msg = str(info.value)
    assert words in msg, msg
    assert msg.startswith(f"{crit}:3: plugins.0: plugin 'bad_plugin.py'") and "\n" not in msg


def test_missing_plugins_are_one_line(tmp_path):
    crit = tmp_path / "c.yaml"
    crit.write_text("plugins: [gone.py, no_such_module_for_rvmsim]\n")
    with pytest.raises(CriteriaError, match=r"c.yaml:1: plugins.0: plugin 'gone.py': "
                                            r"plugin file not found"):
        C.load_criteria(crit)
    crit.write_text("plugins: [no_such_module_for_rvmsim]\n")
    with pytest.raises(CriteriaError, match="cannot import the plugin .No module named"):
        C.load_criteria(crit)


def test_entry_point_plugins_load_by_name(tmp_path, monkeypatch):
    """An installed package offers its ECs under the entry-point group rvmsim.criteria."""
    dist = tmp_path / "acme_rvm-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: acme_rvm\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(
        "[rvmsim.criteria]\nacme = tests.criteria.ec_plugin_example\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert resolve_plugin("acme", tmp_path) == "tests.criteria.ec_plugin_example"
    crit = tmp_path / "c.yaml"
    crit.write_text("plugins: [acme]\n")
    assert C.load_criteria(crit).ids == EC_IDS + ("acme-board-centred",)


def test_definitions_check_their_fields():
    g = LabelGroup("g", (1,))
    with pytest.raises(TypeError, match="measure must be a function"):
        EcDefinition("a", "a", "", (g,), None)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="labels must be ids"):
        LabelGroup("g", (300,))
    ec = EcDefinition("a", "a", "", [g], lambda s, o: None)  # type: ignore[arg-type]
    assert ec.groups == (g,) and ec.default_criterion().sigmoid is None


def test_the_documented_worked_example_is_the_tested_plugin():
    doc = (ROOT / "docs" / "criteria.md").read_text()
    block = doc.split('```python title="acme/board_centred.py"\n', 1)[1].split("```", 1)[0]
    assert block == EXAMPLE.read_text()
