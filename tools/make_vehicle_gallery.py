"""Render the six bundled vehicles small and tile them into docs/img/vehicles.png.

    python tools/make_vehicle_gallery.py
"""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402

from rvmsim import labels as L  # noqa: E402
from rvmsim._io import write_png  # noqa: E402
from rvmsim.render import render_fisheye  # noqa: E402
from rvmsim.scene import load_scene  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    tiles = []
    for letter in "abcdef":
        scene = load_scene(ROOT / "scenes" / f"vehicle_{letter}.yaml")
        img = render_fisheye(scene, camera=scene.fisheye_camera().scaled(0.25))
        tiles.append(np.concatenate([img.color, L.colorize(img.labels)], axis=0))
    top = np.concatenate(tiles[:3], axis=1)
    bottom = np.concatenate(tiles[3:], axis=1)
    out = write_png(ROOT / "docs" / "img" / "vehicles.png", np.concatenate([top, bottom], axis=0))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
