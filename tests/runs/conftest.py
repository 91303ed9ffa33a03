"""Fixtures of the run tests: the tuning tests' render cache and finished run (the runs read
here are written by :func:`rvmsim.tune.tune`)."""

from __future__ import annotations

from ..tune.conftest import cache, clean  # noqa: F401  (fixtures, found by name)
