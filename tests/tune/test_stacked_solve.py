"""Every member's sub-solves at once (tune.StackedSolves, robust tuning's ``mean`` solve):
exactly the mean of each member's own EcSolver, also where a member's objects are cut, out
of view or behind the plane; a plugin's stack solve that breaks the API is one line."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim import labels as L
from rvmsim.criteria import default_criteria
from rvmsim.errors import CriteriaError
from rvmsim.isp import IspParams
from rvmsim.tune import EcSolver, MembersSolver
from rvmsim.search import TuningConfig
from rvmsim.tune.stacked_solve import StackedSolves

from .test_batched_members import members  # noqa: F401 - the fixture
from .test_robust import small  # noqa: F401 - the fixture (a small scene, its own cache)


def _reference(solvers: list[EcSolver], p: IspParams) -> IspParams:
    """Each member solved on its own, the mean over the members that set a parameter."""
    solved = [s(p) for s in solvers]
    names = list(dict.fromkeys(n for s in solvers for n in s.names))
    return p.replace(**{n: float(np.mean([getattr(q, n) for s, q in zip(solvers, solved)
                                          if n in s.names])) for n in names})


@pytest.fixture(scope="module")
def solvers(members):  # noqa: F811 - the fixture above
    mem, _ = members
    config = TuningConfig.model_validate({"output": {"size": [320, 180]}})
    space = config.space(mem[0].camera)
    no_board = mem[1].labels.copy()
    no_board[no_board == L.BOARD] = L.GROUND
    images = [m.labels for m in mem] + [no_board]
    return [EcSolver(im, config.output_spec(), default_criteria(), space)
            for im in images], space


def test_stacked_solves_are_the_mean_of_each_members_solve(solvers):
    found, space = solvers
    assert "adv_h_scale" not in found[-1].names  # the member without a board
    stacked = StackedSolves(found)
    assert stacked.applies
    rng = np.random.default_rng(11)
    ps = [space.params(space.low + rng.random(len(space.low)) * (space.high - space.low))
          for _ in range(60)]
    # views where parts of the outlines leave the plane or the image
    ps += [IspParams(fov=210.0, rad=float(space.high[1]), zoom=0.25),
           IspParams(fov=150.0, rad=float(space.low[1]), zoom=1.45, v_shift=80.0,
                     adv_v_shift=0.8, adv_h_shift=-0.4)]
    changed = 0
    for p in ps:
        want = _reference(found, p)
        assert stacked(p) == want
        assert MembersSolver(found)(p) == want
        changed += want != p
    assert changed > len(ps) // 2


def test_a_plugin_whose_stack_solve_disagrees_is_refused_when_it_loads(tmp_path):
    plugin = tmp_path / "acme_solve.py"
    plugin.write_text(
        "import numpy as np\n"
        "from rvmsim.criteria import EcDefinition, LabelGroup, SubSolve\n"
        "G = LabelGroup('board', (6,))\n"
        "def measure(src, options):\n    return None\n"
        "def solve(xy, params, output, target):\n    return 1.0\n"
        "def solve_stack(xy, starts, params, output, target):\n"
        "    return np.full(len(starts) - 1, 2.0)\n"
        "ECS = [EcDefinition('acme-b', 'b', '', (G,), measure,"
        " sub_solve=SubSolve('adv_h_scale', (6,), solve, solve_stack=solve_stack))]\n")
    from rvmsim.criteria import load_plugin

    with pytest.raises(CriteriaError, match="solve_stack gives") as err:
        load_plugin(str(plugin))
    assert "acme-b" in str(err.value) and "\n" not in str(err.value)
