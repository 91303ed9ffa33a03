"""Imported by the worker fork server (:data:`rvmsim._procs.WORKER_PRELOAD`): pyrender,
on the platform :func:`rvmsim._optional.import_pyrender` chooses, so that a render worker
starts with it (a quarter of a second less per render)."""

from .._optional import import_pyrender

import_pyrender()
