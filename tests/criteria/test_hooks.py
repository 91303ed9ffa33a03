"""The EC definition's optional hooks (sub-solve, feasibility reason): their validation, the
registry-driven sub-solves of tuning (the paper's and a plugin's), and a plugin EC with both
hooks tuned with ``cmaes-solved`` and swept over a mount where its object is out of view."""

from __future__ import annotations

import dataclasses
import pickle
from pathlib import Path

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.batch import LocalExecutor, infeasible_ecs, load_sweep, run_sweep
from rvmsim.criteria import (
    Criteria,
    Criterion,
    EcDefinition,
    Measurement,
    SubSolve,
    builtin_ecs,
    criteria_from_text,
    default_criteria,
    load_plugin,
    range_middle,
    range_zero,
)

from rvmsim.errors import CriteriaError
from rvmsim.isp import OutputSpec, process
from rvmsim.runs import RunStore
from rvmsim.tune import EcSolver, SearchOptions, SearchSettings, search_scene
from rvmsim.search import TuningConfig

from ..batch.conftest import small_scene_text
from ..conftest import small_render

PLUGIN = Path(__file__).with_name("ec_plugin_hooks.py")
EC = "acme-guide2-height"
OUT = OutputSpec(320, 180)


def _criteria(tmp_path: Path, extra: str = "  3-2: {enabled: false}\n") -> Criteria:
    path = tmp_path / "criteria.yaml"
    path.write_text(f"name: hooks\nplugins: [{PLUGIN}]\ncriteria:\n{extra}")
    return criteria_from_text(path.read_text(), str(path))


def _guide2_height(labels: np.ndarray) -> float | None:
    """The plugin's EC computed independently: guideline 2's rows in the RVM label image."""
    rows = np.nonzero((labels == L.guide_cross(2)).any(axis=1))[0]
    if rows.size == 0:
        return None
    return 100.0 * ((rows.min() + rows.max()) / 2.0 + 0.5) / labels.shape[0]


def _wholly_inside(labels: np.ndarray, label: int) -> bool:
    ys, xs = np.nonzero(labels == label)
    h, w = labels.shape
    return bool(len(xs)) and xs.min() > 0 and ys.min() > 0 and xs.max() < w - 1 \
        and ys.max() < h - 1


# ---------------------------------------------------------------------------- validation
def _solve(xy, params, output, target):
    return 0.0


def _measure(src, options):
    return Measurement(None)


def _reason(context, criterion, options):
    return None


@pytest.mark.parametrize("kwargs, error, text", [
    ({"param": "adv_v_shfit"}, ValueError, "must be an ISP parameter"),
    ({"labels": ()}, TypeError, "labels must be"),
    ({"labels": (300,)}, TypeError, "labels must be"),
    ({"labels": "42"}, TypeError, "labels must be"),
    ({"solve": "not a function"}, TypeError, "solve must be a function"),
    ({"target": 50.0}, TypeError, "target must be a function"),
    ({"order": 1.5}, TypeError, "order must be an integer"),
])
def test_a_sub_solve_checks_its_fields(kwargs, error, text):
    args = {"param": "adv_v_shift", "labels": (L.guide_cross(2),), "solve": _solve, **kwargs}
    with pytest.raises(error, match=text):
        SubSolve(**args)


def test_a_sub_solve_keeps_labels_as_a_tuple_and_defaults_to_the_range_middle():
    s = SubSolve("adv_h_shift", [np.uint8(42)], _solve)
    assert s.labels == (42,) and type(s.labels[0]) is int
    assert s.target is range_middle and s.order == 0


def test_an_ec_definition_checks_its_hooks():
    base = dict(id="x", name="x", unit="", groups=(), measure=_measure)
    with pytest.raises(TypeError, match="sub_solve must be an rvmsim.criteria.SubSolve"):
        EcDefinition(**base, sub_solve=_solve)
    with pytest.raises(TypeError, match="infeasibility must be a function"):
        EcDefinition(**base, infeasibility="guideline 2 is missing")
    ec = EcDefinition(**base, sub_solve=SubSolve("zoom", (1,), _solve), infeasibility=_reason)
    # without a plugin a definition pickles by value, hooks included
    again = pickle.loads(pickle.dumps(ec))
    assert again == ec and again.sub_solve.solve is _solve and again.infeasibility is _reason


def test_targets_from_the_range():
    assert range_middle(Criterion("x", 40, 50)) == 45.0
    assert range_middle(Criterion("x", None, 50)) is None
    assert range_zero(Criterion("x", None, 5)) == 0.0
    assert range_zero(Criterion("x", -1, 5)) == 0.0
    assert range_zero(Criterion("x", 1, 5)) is None
    assert range_zero(Criterion("x", 0, None)) is None


def test_a_plugin_with_hooks_pickles_by_reference():
    ec = next(e for e in load_plugin(str(PLUGIN)) if e.id == EC)
    assert ec.sub_solve is not None and ec.infeasibility is not None
    assert pickle.loads(pickle.dumps(ec)) is ec


@pytest.mark.parametrize("body, text", [
    ("return 'up'", "the sub-solve's solve returned 'up'"),
    ("return float('nan')", "the sub-solve's solve returned nan"),
    ("raise ZeroDivisionError('no')", "sub-solve fails on a square of plane points "
                                      r"\(ZeroDivisionError: no\)"),
])
def test_a_plugin_whose_sub_solve_breaks_the_api_is_refused_on_load(tmp_path, body, text):
    path = tmp_path / "bad_solve.py"
    path.write_text(
        "from rvmsim.criteria import EcDefinition, Measurement, SubSolve\n"
        "def m(src, options):\n    return Measurement(None)\n"
        f"def s(xy, params, output, target):\n    {body}\n"
        "ECS = [EcDefinition('bad', 'bad', '', (), m, default_range=(0, 1),\n"
        "                    sub_solve=SubSolve('zoom', (1,), s))]\n")
    with pytest.raises(CriteriaError, match=text):
        load_plugin(str(path))


def test_a_plugin_whose_hook_is_not_a_function_is_refused_on_load(tmp_path):
    path = tmp_path / "bad_hook.py"
    path.write_text(
        "from rvmsim.criteria import EcDefinition, Measurement\n"
        "def m(src, options):\n    return Measurement(None)\n"
        "ECS = [EcDefinition('bad', 'bad', '', (), m, infeasibility=3)]\n")
    with pytest.raises(CriteriaError, match="infeasibility must be a function"):
        load_plugin(str(path))


# ---------------------------------------------------------------------------- EcSolver
def test_two_ecs_solving_one_parameter_are_refused(tmp_path):
    images = small_render("a")
    crit = _criteria(tmp_path, extra="  3-2: {enabled: true}\n")
    cfg = TuningConfig.model_validate({"output": {"size": [OUT.width, OUT.height]}})
    with pytest.raises(CriteriaError) as err:
        EcSolver(images.labels, OUT, crit, cfg.space(images.camera))
    msg = str(err.value)
    assert "\n" not in msg and "ECs 3-2 and acme-guide2-height both solve adv_v_shift" in msg
    assert "criteria.yaml" in msg
    # no conflict when the parameter is not tuned: nothing solves it
    cfg = TuningConfig.model_validate({"tuned": ["zoom", "adv_h_shift"]})
    assert EcSolver(images.labels, OUT, crit, cfg.space(images.camera)).names == (
        "adv_h_shift",)


def test_a_replacement_without_a_hook_does_not_solve():
    images = small_render("a")
    ecs = tuple(dataclasses.replace(e, sub_solve=None) if e.id == "4-1" else e
                for e in builtin_ecs())
    crit = Criteria("replaced", dict(default_criteria().items), ecs=ecs)
    space = TuningConfig().space(images.camera)
    assert EcSolver(images.labels, OUT, default_criteria(), space).names == (
        "adv_h_scale", "adv_v_shift", "adv_h_shift")  # the solve order: 4-1, 3-2, 3-1
    solver = EcSolver(images.labels, OUT, crit, space)
    assert solver.names == ("adv_v_shift", "adv_h_shift") and "4-1" not in solver.targets


def test_the_plugin_solve_puts_its_ec_on_target(tmp_path):
    """Random candidates solved by the registry-driven solver with the plugin's criteria
    (3-2 off): guideline 2 at 65 % (the middle of its default range) within a row, and the
    paper's 3-1 and 4-1 still solved, measured on the whole RVM label image."""
    images = small_render("a")
    crit = _criteria(tmp_path)
    cfg = TuningConfig.model_validate({"output": {"size": [OUT.width, OUT.height]}})
    space = cfg.space(images.camera)
    solver = EcSolver(images.labels, OUT, crit, space)
    assert solver.names == ("adv_h_scale", "adv_v_shift", "adv_h_shift")
    assert solver.targets == {"4-1": 1.0, EC: 65.0, "3-1": 0.0}
    ranges = {r.name: r for r in space.ranges}
    checked = 0
    rng = np.random.default_rng(11)
    for x in rng.uniform(space.low, space.high, size=(80, len(space.names))):
        p = solver(space.params(x))
        r = ranges["adv_v_shift"]
        if not r.low + 1e-9 < p.adv_v_shift < r.high - 1e-9:
            continue
        _, labels = process(None, images.labels, p, OUT)
        if not _wholly_inside(labels, L.guide_cross(2)):
            continue
        assert abs(_guide2_height(labels) - 65.0) <= 100.0 / OUT.height, p
        checked += 1
    assert checked >= 15


# ---------------------------------------------------------------------------- tuned, swept
def test_cmaes_solved_tunes_the_plugin_ec_onto_its_target(tmp_path):
    """Two worker processes: the solver reaches them with the plugin's hook (by reference to
    the plugin file, which is not importable by name)."""
    images = small_render("a")
    crit = _criteria(tmp_path)
    config = TuningConfig.model_validate({"output": {"size": [OUT.width, OUT.height]}})
    store = RunStore(":memory:")
    outcome = search_scene(images, SearchSettings(config, crit, "cmaes-solved", budget=40),
                           store, options=SearchOptions(workers=2))
    best = outcome.best
    assert best is not None and "adv_v_shift" in outcome.space.names
    _, labels = process(None, images.labels, best.params, OUT)
    measured = _guide2_height(labels)
    assert measured is not None and abs(measured - 65.0) <= 100.0 / OUT.height
    assert best.ecs[EC].value == pytest.approx(measured, abs=1e-9)
    # every stored candidate was solved: guideline 2 sits at 65 % wherever it is measured
    values = [t.ecs[EC].value for t in store.trials() if t.ecs[EC].value is not None]
    assert len(values) >= 20 and np.median(np.abs(np.array(values) - 65.0)) < 1.0
    store.close()


SWEEP = """\
name: guideline 2 out of view
base_scene: base.yaml
axes:
  yaw_deg: [0, 180]
tune:
  strategy: cmaes-solved
  budget: 24
  seed: 0
  config: {output: {size: [320, 180]}}
  criteria: criteria.yaml
  recheck: {rounds: 0}
sensitivity: false
"""


def test_a_sweep_reports_the_plugin_ec_infeasible_where_its_object_is_out_of_view(tmp_path):
    # no variation section: the verdicts are the point, not the yields
    (tmp_path / "base.yaml").write_text(small_scene_text("a", variation=None))
    (tmp_path / "criteria.yaml").write_text(
        f"name: hooks\nplugins: [{PLUGIN}]\ncriteria:\n  3-2: {{enabled: false}}\n")
    (tmp_path / "sweep.yaml").write_text(SWEEP)
    spec = load_sweep(tmp_path / "sweep.yaml")
    res = run_sweep(spec, tmp_path / "out", executor=LocalExecutor(1))
    straight, turned = (res.results[p.key] for p in res.points)
    assert turned["verdict"] == "infeasible"
    assert {"ec": EC, "reason": f"{EC}: guideline 2 is not in the fisheye image",
            "short": f"{EC}: no guideline 2"} in turned["infeasible"]
    assert f"{EC}: guideline 2 is not in the fisheye image" in turned["reason"]
    assert straight["verdict"] != "infeasible" and straight["reason"] is None
    assert straight["infeasible"] == []


def test_infeasible_ecs_ask_only_enabled_ecs_with_a_reason(tmp_path):
    """The plugin's reason is asked only when its EC is enabled, and reasons come in the
    criteria's order (the plugin's EC after the paper's)."""
    from rvmsim.render import cached_render
    from rvmsim.scene import scene_from_dict
    import yaml

    doc = yaml.safe_load(small_scene_text("a"))
    doc["camera"]["mount"]["yaw_deg"] = 180.0
    scene = scene_from_dict(doc, source="test")
    images, _ = cached_render(scene)
    crit = _criteria(tmp_path)
    found = [x.ec for x in infeasible_ecs(scene, images.camera, images.labels, crit)]
    assert found[-1] == EC and found == [e for e in crit.ids if e in found]
    off = _criteria(tmp_path, extra=f"  3-2: {{enabled: false}}\n  {EC}: {{enabled: false}}\n")
    assert EC not in [x.ec for x in infeasible_ecs(scene, images.camera, images.labels, off)]
