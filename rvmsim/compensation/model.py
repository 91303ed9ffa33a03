"""The compensation model as a frozen dataclass, and reading it (``--compensation
FILE|default``).

The YAML schema is :class:`rvmsim.scene.CompensationSpec`; a compensation file holds its keys
at the top level, or a ``compensation`` section (so a variation file with one serves too).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from .._io import input_error_from_validation, key_lines, parse_yaml_mapping, read_text
from ..errors import CompensationError
from ..scene import DEFAULT_RANGES, CompensationSpec

__all__ = ["CompensationModel", "DEFAULT_COMPENSATION", "compensation_from_spec",
           "compensation_from_dict", "load_compensation", "compensation_for",
           "measured_load_index"]


@dataclass(frozen=True)
class CompensationModel:
    """What a car's end-of-line step writes and how well its station measures.

    Attributes
    ----------
    params : tuple of str
        The ISP parameters written per car (:data:`rvmsim.scene.COMPENSABLE_PARAMS`).
    ranges : tuple of (str, float, float)
        Allowed per-car offset from the platform setting per parameter (``h_pan``: the
        magnitude of the view axis's turn, degrees, whatever its direction; ``v_pan`` has
        none: it is that turn's direction).
    angle_sigma_deg, position_sigma_mm : float
        The station's measurement error, 1 σ per axis (assumptions; docs/compensation.md).
    measured_at : str or None
        The load state the station measures at (None: the variation's first).
    reference : str
        ``site`` or ``ground``: the ground points the reference-point law keeps where the
        nominal car shows them (:func:`rvmsim.compensation.reference_points`).
    source : str
        Where the model came from (a file, ``default``).
    law : str
        How the per-car values are chosen: ``ec-solve`` (every enabled EC on the car's own
        picture, the largest least margin; :mod:`rvmsim.percar`) or ``reference-points``
        (:class:`~rvmsim.compensation.CompensationLaw` alone).
    budget : int
        ``ec-solve``: the EC evaluations one car may cost (the search; a car that fails
        within it is then checked on a grid of the allowed ranges, which costs more).
    edge_sigma_px : float
        The body's edge as the station finds it on the capture, 1 σ, fisheye px (the error
        the ECs that read the body inherit instead of the pose's).
    marginal : str
        ``fail`` (default) or ``accept``: what the station does with a car whose least EC
        margin is inside the station's uncertainty of that EC.
    stop : str
        ``ec-solve``: ``nominal`` (default), the search stops once the car's least EC margin
        is the nominal car's with the platform setting (and no EC is inside the station's
        uncertainty): the car is as good as the design; ``never``: it maximises the least
        margin until its budget is spent.
    """

    params: tuple[str, ...] = ("h_pan", "v_pan", "tilt")
    ranges: tuple[tuple[str, float, float], ...] = (("h_pan", 0.0, 3.0), ("tilt", -3.0, 3.0))
    angle_sigma_deg: float = 0.1
    position_sigma_mm: float = 1.0
    measured_at: str | None = None
    reference: str = "site"
    source: str = "built-in default"
    law: str = "ec-solve"
    budget: int = 24
    edge_sigma_px: float = 0.3
    marginal: str = "fail"
    stop: str = "nominal"
    #: Where the model's keys sit in ``source`` (``compensation`` for a section; "" at the
    #: top level), for messages naming a key.
    key_prefix: str = field(default="", compare=False)

    def key(self, name: str) -> str:
        """``name``'s key as ``source`` spells it (``compensation.law``)."""
        return f"{self.key_prefix}.{name}" if self.key_prefix else name

    def range_of(self, name: str) -> tuple[float, float]:
        """The allowed offset of parameter ``name`` (±inf for ``v_pan``)."""
        for n, low, high in self.ranges:
            if n == name:
                return low, high
        return (-float("inf"), float("inf")) if name == "v_pan" else DEFAULT_RANGES[name]

    @property
    def pans(self) -> bool:
        """Whether the pans are written (the view axis turns)."""
        return "h_pan" in self.params

    def with_station(self, angle_sigma_deg: float, position_sigma_mm: float,
                     edge_sigma_px: float | None = None) -> CompensationModel:
        """The same model with another station accuracy (for the yield-against-σ curve;
        the edge's σ unchanged unless given)."""
        return dataclasses.replace(
            self, angle_sigma_deg=angle_sigma_deg, position_sigma_mm=position_sigma_mm,
            edge_sigma_px=self.edge_sigma_px if edge_sigma_px is None else edge_sigma_px)

    def as_dict(self) -> dict[str, object]:
        """JSON-ready description (what robustness.json and eol.json record)."""
        return {"source": self.source, "params": list(self.params),
                "ranges": {n: list(self.range_of(n)) for n in self.params if n != "v_pan"},
                "station": {"angle_sigma_deg": self.angle_sigma_deg,
                            "position_sigma_mm": self.position_sigma_mm,
                            "edge_sigma_px": self.edge_sigma_px,
                            "measured_at": self.measured_at, "marginal": self.marginal},
                "reference": self.reference, "law": self.law, "budget": self.budget,
                "stop": self.stop}


#: The documented defaults (docs/compensation.md): the view's rotation, ±3°, a station of
#: 0.1° and 1 mm.
DEFAULT_COMPENSATION = CompensationModel()


def compensation_from_spec(spec: CompensationSpec, source: str = "<dict>",
                           key_prefix: str = "") -> CompensationModel:
    """The dataclass of a validated :class:`~rvmsim.scene.CompensationSpec` (its keys under
    ``key_prefix`` in ``source``)."""
    params = tuple(spec.params)
    ranges = tuple((n, *spec.ranges.get(n, DEFAULT_RANGES[n])) for n in params if n != "v_pan")
    st = spec.station
    return CompensationModel(params, ranges, st.angle_sigma_deg, st.position_sigma_mm,
                             st.measured_at, spec.reference, source, spec.law, spec.budget,
                             st.edge_sigma_px, st.marginal, spec.stop, key_prefix)


def compensation_from_dict(doc: dict[str, Any]) -> CompensationModel:
    """The model :meth:`CompensationModel.as_dict` described (a run's stored settings).
    A description without ``law`` was stored before there was a choice (runs of
    2026-12-05 and earlier): its law is ``reference-points``, the only one then.

    Raises
    ------
    ValueError
        ``doc`` is not such a description (pydantic's ValidationError names the key).
    """
    data = {k: doc[k] for k in ("params", "ranges", "station", "reference", "law", "budget",
                                "stop") if k in doc}
    data.setdefault("law", "reference-points")
    spec = CompensationSpec.model_validate(data)
    return compensation_from_spec(spec, str(doc.get("source", "<run>")))


def load_compensation(path: str | Path) -> CompensationModel:
    """Read a compensation file: the keys of :class:`~rvmsim.scene.CompensationSpec` at its
    top level, or under a ``compensation`` key (a variation file with that section), or
    under ``variation.compensation`` (a scene file with one).

    Raises
    ------
    CompensationError
        Unreadable file, bad YAML, or an invalid key: one line naming file, line and key.
    """
    path = Path(path)
    text = read_text(path, CompensationError, what="compensation file")
    data = parse_yaml_mapping(text, str(path), CompensationError, "a compensation file",
                              empty_ok=True)
    lines = key_lines(text)
    prefix: tuple[str, ...] = ()
    variation = data.get("variation")
    if isinstance(variation, dict) and "compensation" in variation:  # a scene file
        data, prefix = variation, ("variation",)
    if "compensation" in data:
        section = data["compensation"]
        prefix += ("compensation",)
        if not isinstance(section, dict):
            raise CompensationError(str(path), ".".join(prefix), "must be a mapping",
                                    lines.get(prefix))
        data = section
    try:
        spec = CompensationSpec.model_validate(data)
    except ValidationError as err:
        shifted = {k[len(prefix):]: v for k, v in lines.items() if k[:len(prefix)] == prefix}
        e = input_error_from_validation(err, str(path), shifted, CompensationError)
        if prefix:
            key = ".".join(prefix + ((e.key,) if e.key else ()))
            raise CompensationError(e.file, key, e.message, e.line) from None
        raise e from None
    return compensation_from_spec(spec, str(path), ".".join(prefix))


def compensation_for(value: str | Path | None) -> CompensationModel | None:
    """``--compensation``'s model: None without one, the defaults for ``default``, else the
    file's (:func:`load_compensation`)."""
    if value is None:
        return None
    if str(value) == "default":
        return DEFAULT_COMPENSATION
    return load_compensation(value)


def measured_load_index(model: CompensationModel, load_names: Sequence[str]) -> int:
    """The index of the load state the station measures at among ``load_names``.

    Raises
    ------
    CompensationError
        ``measured_at`` names no load state of the variation.
    """
    if model.measured_at is None:
        return 0
    if model.measured_at not in load_names:
        raise CompensationError(model.source, "station.measured_at",
                                f"{model.measured_at!r} is not a load state of the variation "
                                f"({', '.join(load_names)})")
    return list(load_names).index(model.measured_at)
