"""The regulations rvmsim judges against, one package each: ``fmvss111`` (FMVSS No. 111
beyond the paper), ``unr158`` (UN R158) and ``jp`` (Japan).  Each holds its test site
(``site.yaml``, :mod:`rvmsim.scene.sitedefs`' format), its ECs (``ecs.py``, a criteria
plugin: :mod:`rvmsim.criteria.registry`) and its criteria set (``criteria.yaml``), and
:mod:`.objects` and :mod:`.siteobjects` hold what their ECs share (silhouettes and surface
samples of test objects).  The paper's eleven ECs are the EC framework's built-ins
(:mod:`rvmsim.criteria.builtin`).  A regulation of your own: docs/extending.md.

The scene loader and the criteria loader read the site and criteria files as data
(:data:`rvmsim.scene.BUNDLED_SITES`, :data:`rvmsim.criteria.BUNDLED_CRITERIA`); nothing
below this package imports it.
"""

from __future__ import annotations

#: The bundled regulations: the name of each package here.
REGULATIONS = ("fmvss111", "unr158", "jp")

__all__ = ["REGULATIONS"]
