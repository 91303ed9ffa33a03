"""Mesh primitives: cylinder sides, disks and swept blocks face outward."""

from __future__ import annotations

import numpy as np
import pytest

from rvmsim.scene import BlockPart, cylinder_side, disk, swept_block


def test_primitives_face_outward():
    tube = cylinder_side(0.15, 0.0, 0.8, 0, 360, (1.0, 2.0))
    radial = tube.triangles_center[:, [0, 2]] - [1.0, 2.0]
    assert np.all(np.einsum("ij,ij->i", tube.face_normals[:, [0, 2]], radial) > 0)
    top = disk(0.15, 0.8, (1.0, 2.0))
    assert np.all(top.face_normals[:, 1] < -0.99)  # up is −Y
    block = swept_block(BlockPart(width=1.8, bottom=0.3, top=0.6, depth=0.3, sweep=0.2, lean_deg=8))
    assert block.is_watertight and block.volume > 0
    lo, hi = block.bounds
    assert hi[2] == pytest.approx(0.0, abs=1e-3)  # rearmost point on the bumper plane
    assert -lo[1] == pytest.approx(0.6) and -hi[1] == pytest.approx(0.3)
