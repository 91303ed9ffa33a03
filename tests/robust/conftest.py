"""Shared pieces of the robustness tests (their small scenes: :mod:`tests.scenes`)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: ±1° on every angle, no position tolerance, no load states: one viewpoint.
ANGLES_ONLY = {"mount": {a: {"uniform": {"half_width": 1.0}}
                         for a in ("yaw_deg", "pitch_deg", "roll_deg")}}
