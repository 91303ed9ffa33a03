"""The one place where heavy or optional third-party modules are imported on first use.

Everything else in rvmsim imports at module top.  These are deferred because importing
them has a cost or a condition that most commands never need to pay:

- ``pyrender`` creates its OpenGL platform on import, so ``PYOPENGL_PLATFORM`` must be set
  first (headless EGL unless the user says otherwise), and only commands that render need GL;
- ``distributed`` (Dask) is an optional extra, needed only with ``--scheduler``;
- ``playwright`` is an optional extra, needed only to print the sign-off PDF;
- ``cmaes`` with ``scipy.stats`` (0.35 s more than the rest of rvmsim needs) and ``trimesh``
  (0.6 s) are paid again by every spawned worker and child command, while only a CMA-ES
  search, the shade pose search, drawing variation samples (:func:`cma_class`,
  :func:`scipy_stats`) and building meshes (:func:`import_trimesh`) use them; a worker
  that evaluates candidates starts without them.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType
from typing import TYPE_CHECKING

from .errors import RvmsimError

if TYPE_CHECKING:
    from cmaes import CMA

__all__ = ["import_pyrender", "import_distributed", "import_playwright_sync_api", "cma_class",
           "scipy_stats", "import_trimesh"]


def import_pyrender() -> ModuleType:
    """The ``pyrender`` module, imported after choosing headless EGL unless
    ``PYOPENGL_PLATFORM`` already names a platform."""
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    return importlib.import_module("pyrender")


def _installed(module: str, missing: str) -> ModuleType:
    """``module``, or an RvmsimError with the one line ``missing`` when it is not installed."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise RvmsimError(missing) from None


def import_distributed() -> ModuleType:
    """The ``distributed`` (Dask) module; RvmsimError (how to install it) when it is missing."""
    return _installed("distributed", "--scheduler needs the 'distributed' package "
                                     "(pip install distributed)")


def import_playwright_sync_api() -> ModuleType:
    """``playwright.sync_api``; RvmsimError (how to install it, or --no-pdf) when it is
    missing."""
    return _installed("playwright.sync_api", "printing the PDF needs Playwright (pip install "
                                             "playwright) and Debian's chromium, or give --no-pdf")


def cma_class() -> type[CMA]:
    """``cmaes.CMA``, the CMA-ES optimiser (imported on first use)."""
    cma: type[CMA] = importlib.import_module("cmaes").CMA
    return cma


def scipy_stats() -> ModuleType:
    """``scipy.stats`` (imported on first use)."""
    return importlib.import_module("scipy.stats")


def import_trimesh() -> ModuleType:
    """The ``trimesh`` module (imported on first use: only building meshes needs it)."""
    return importlib.import_module("trimesh")
