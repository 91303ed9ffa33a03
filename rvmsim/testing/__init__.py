"""What rvmsim's tests and benchmarks (``tests/``, ``tools/``) share, in a source checkout:
small scenes of the bundled vehicles (:mod:`.scenes`), synthetic and real captures for
validation (:mod:`.captures`, :mod:`.hard_captures`) and an end-of-line station's inputs
(:mod:`.stations`).  Not part of the product's API: these read the checkout's ``scenes/``
folder and render real images, so importing a module here costs nothing, using it does.
"""

from __future__ import annotations

__all__: list[str] = []
