"""The one place where heavy or optional third-party modules are imported on first use.

Everything else in rvmsim imports at module top.  These three are deferred because importing
them has a cost or a condition that most commands never need to pay:

- ``pyrender`` creates its OpenGL platform on import, so ``PYOPENGL_PLATFORM`` must be set
  first (headless EGL unless the user says otherwise), and only commands that render need GL;
- ``distributed`` (Dask) is an optional extra, needed only with ``--scheduler``;
- ``playwright`` is an optional extra, needed only to print the sign-off PDF.
"""

from __future__ import annotations

import importlib
import os
from types import ModuleType

from .errors import RvmsimError

__all__ = ["import_pyrender", "import_distributed", "import_playwright_sync_api"]


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
