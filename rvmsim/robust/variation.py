"""Production variation as frozen dataclasses: per-axis mount tolerances and load states.

Read from a scene's ``variation`` section (:func:`variation_from_scene`) or a variation file
of the same keys (:func:`load_variation`); :func:`variation_for` chooses between them as
``--variation`` does (``rvmsim robustness``, ``rvmsim tune --robust``).  The YAML schema is
:class:`rvmsim.scene.VariationSpec`.  Conventions (frames, signs): see
:mod:`rvmsim.scene.variation`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from .._io import input_error_from_validation, key_lines, parse_yaml_mapping, read_text
from ..errors import VariationError
from ..scene import MOUNT_AXES, AxisSpec, Scene, VariationSpec

__all__ = ["AxisDistribution", "LoadState", "Variation", "load_variation",
           "variation_from_scene", "variation_from_spec", "variation_for", "NOMINAL_LOAD",
           "MOUNT_AXES"]


@dataclass(frozen=True)
class AxisDistribution:
    """One mount axis: ``kind`` ``"fixed"`` (no variation), ``"uniform"`` on
    [−half_width, half_width] or ``"normal"`` (σ ``sigma``, truncated at ±``truncate`` σ);
    mm for positions, degrees for angles."""

    kind: str = "fixed"
    half_width: float = 0.0
    sigma: float = 0.0
    truncate: float = 3.0

    @property
    def bound(self) -> float:
        """Largest absolute offset."""
        return self.half_width if self.kind == "uniform" else (
            self.sigma * self.truncate if self.kind == "normal" else 0.0)

    @property
    def varies(self) -> bool:
        return self.bound > 0.0

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Offsets at probabilities ``u`` in (0, 1) (the inverse distribution function)."""
        u = np.asarray(u, dtype=np.float64)
        if self.kind == "uniform":
            return (2.0 * u - 1.0) * self.half_width
        if self.kind == "normal" and self.sigma > 0:
            # scipy.stats is imported where it is used, not at module top: it takes 0.25 s,
            # and every command that tunes imports this module before its first candidate.
            from scipy.stats import truncnorm

            return np.asarray(truncnorm.ppf(u, -self.truncate, self.truncate)) * self.sigma
        return np.zeros_like(u)


@dataclass(frozen=True)
class LoadState:
    """A discrete load state: camera height change (mm, negative = lower), body pitch
    (degrees, rear down > 0), probability (the weights normalised)."""

    name: str
    height_mm: float = 0.0
    pitch_deg: float = 0.0
    probability: float = 1.0


#: The load state of a variation without load states: the scene as modelled.
NOMINAL_LOAD = LoadState("nominal")


@dataclass(frozen=True)
class Variation:
    """Mount tolerances (one :class:`AxisDistribution` per :data:`MOUNT_AXES` entry, same
    order), load states (probabilities sum to 1), the rendered positions per varying
    position axis, and the least production yield (0–1) that passes (None: not given)."""

    axes: tuple[AxisDistribution, ...] = tuple(AxisDistribution() for _ in MOUNT_AXES)
    load_states: tuple[LoadState, ...] = (NOMINAL_LOAD,)
    position_levels: int = 2
    source: str = "<none>"
    min_yield: float | None = None

    def axis(self, name: str) -> AxisDistribution:
        """The distribution of axis ``name`` (one of :data:`MOUNT_AXES`)."""
        return self.axes[MOUNT_AXES.index(name)]

    def as_dict(self) -> dict[str, object]:
        """JSON-ready description (what robustness.json records)."""
        return {"source": self.source, "position_levels": self.position_levels,
                "mount": {n: vars(a) for n, a in zip(MOUNT_AXES, self.axes)},
                "load_states": [vars(s) for s in self.load_states],
                "min_yield": self.min_yield}


def _axis(spec: AxisSpec | None) -> AxisDistribution:
    if spec is None:
        return AxisDistribution()
    if spec.uniform is not None:
        return AxisDistribution("uniform", half_width=spec.uniform.half_width)
    assert spec.normal is not None
    return AxisDistribution("normal", sigma=spec.normal.sigma, truncate=spec.normal.truncate)


def variation_from_spec(spec: VariationSpec, source: str = "<dict>") -> Variation:
    """The dataclasses of a validated :class:`~rvmsim.scene.VariationSpec`."""
    total = sum(s.weight for s in spec.load_states)
    loads = tuple(LoadState(s.name, s.height_mm, s.pitch_deg, s.weight / total)
                  for s in spec.load_states) or (NOMINAL_LOAD,)
    return Variation(tuple(_axis(getattr(spec.mount, n)) for n in MOUNT_AXES), loads,
                     spec.mount.position_levels, source, spec.min_yield)


def load_variation(path: str | Path) -> Variation:
    """Read a variation file (the keys of a scene's ``variation`` section at its top level).

    Raises
    ------
    VariationError
        Unreadable file, bad YAML, or an invalid key: one line naming file, line and key.
    """
    path = Path(path)
    text = read_text(path, VariationError, what="variation file")
    data = parse_yaml_mapping(text, str(path), VariationError, "a variation file")
    try:
        spec = VariationSpec.model_validate(data)
    except ValidationError as err:
        raise input_error_from_validation(err, str(path), key_lines(text),
                                          VariationError) from None
    return variation_from_spec(spec, str(path))


def variation_from_scene(scene: Scene) -> Variation:
    """The scene's ``variation`` section (validated when the scene was loaded), or no
    variation at all (every axis fixed, one nominal load state) when it has none."""
    if scene.variation is None:
        return Variation(source=f"{scene.source} (no variation section)")
    return variation_from_spec(scene.variation, f"{scene.source}: variation")


def variation_for(scene: Scene, variation_file: str | Path | None) -> Variation:
    """The variation ``scene`` is judged on: the variation file's when one is given
    (``--variation``), else the scene's own ``variation`` section.

    Raises
    ------
    VariationError
        One line naming the file and key: a bad variation file, or no file and a scene
        without a variation section.
    """
    if variation_file is not None:
        return load_variation(variation_file)
    if scene.variation is None:
        raise VariationError(scene.source, "variation", "the scene has no variation section; "
                             "add one (docs/robustness.md) or give --variation FILE")
    return variation_from_scene(scene)
