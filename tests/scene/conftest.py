"""Scene-test helpers: the smallest valid scene document."""

from __future__ import annotations

from typing import Any


def minimal_scene() -> dict[str, Any]:
    """A new copy of the smallest valid scene document (a parametric bumper only)."""
    return {
        "name": "t",
        "camera": {
            "image_size": [640, 480],
            "intrinsics": {"fx": 200.0, "fy": 200.0},
            "mount": {"position": [0.0, -1.0, -0.1], "pitch_deg": 30},
        },
        "vehicle": {"bumper": {"width": 1.8, "bottom": 0.3, "top": 0.6, "depth": 0.3}},
    }
