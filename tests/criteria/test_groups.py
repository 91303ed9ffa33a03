"""Label groups: reading each group inside its window changes no measurement."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.criteria import LabelSource, measure, measure_source
from rvmsim.isp import IspParams, OutputSpec, apply_map, build_map

from ..conftest import small_render


class _Whole(LabelSource):
    """Every measurement reads the whole image (the reference for the group windows)."""

    def window(self, group):
        return (0, 0, self.shape[1], self.shape[0])


@pytest.mark.parametrize("letter", ["a", "c"])
def test_group_windows_change_no_measurement(letter):
    """measure() reads each group from the box of its 8×8 blocks; the values equal reading
    the whole image, on real RVM label images of many views."""
    img = small_render(letter)
    size = (img.camera.width, img.camera.height)
    rng = np.random.default_rng(11)
    for _ in range(25):
        p = IspParams(fov=rng.uniform(160, 200), rad=rng.uniform(200, 420),
                      zoom=rng.uniform(0.3, 1.3), adv_v_shift=rng.uniform(-0.6, 0.6),
                      adv_h_shift=rng.uniform(-0.3, 0.3), v_shift=rng.uniform(-60, 60))
        w, h = rng.choice([(320, 240), (317, 181)])  # also sizes that are not multiples of 8
        labels = apply_map(img.labels, build_map(p, size, OutputSpec(int(w), int(h))))
        fast, ref = measure(labels), measure_source(_Whole(labels))
        assert fast.values == ref.values
        assert fast.details == ref.details




def test_ecs_sharing_a_group_name_must_mean_the_same_labels(tmp_path):
    from rvmsim import labels as L
    from rvmsim.criteria import LabelGroup, load_criteria
    from rvmsim.criteria.groups import unique_groups
    from rvmsim.errors import CriteriaError

    board = LabelGroup("board", (L.BOARD,))
    assert unique_groups([board, LabelGroup("board", (L.BOARD,)), board]) == (board,)
    with pytest.raises(ValueError, match="two different label groups are named 'board'"):
        unique_groups([board, LabelGroup("board", (L.BOARD, L.SKY))])
    (tmp_path / "p.py").write_text(
        "from rvmsim.criteria import EcDefinition, LabelGroup\n"
        "G = LabelGroup('board', (1, 2))\n"
        "ECS = [EcDefinition('sky-board', 'x', '', (G,), lambda s, o: float(s.window(G)[0]))]\n")
    crit = tmp_path / "c.yaml"
    crit.write_text("plugins: [p.py]\n")
    with pytest.raises(CriteriaError, match=r"c.yaml:1: plugins: the selected ECs disagree: "
                                            r"two different label groups are named 'board'"):
        load_criteria(crit)
