"""Test sites as data: site definitions (YAML) placed relative to a scene's vehicle.

A *site definition* lists the test objects of one regulation's test site in rows: each row
a distance behind the vehicle, lateral positions (metres, or fractions of the vehicle's
width), the cylinders' size and marking.  Three ship with rvmsim (:data:`BUNDLED_SITES`):

- ``fmvss111``: FMVSS No. 111's objects A–G (``kind: fmvss111``).  Its values are the
  defaults of a scene's ``test_site`` section (:mod:`rvmsim.scene.fmvss111` reads them from
  the file), rendered with the paper's labels;
- ``unr158``: UN R158's rear-view camera system field of vision (three rows of cylinders);
- ``jp``: Japan's rear-view monitor assessment (JNCAP's poles) where it asks more than R158.

A scene names its sites (``sites: [fmvss111, unr158]``; a name, or a site file relative to
the scene file); :func:`rvmsim.scene.site_scene` gives the scene *at* a site: the same car and camera,
with the site's objects placed behind the car (:class:`SiteObject`, each with its own
labels, :func:`rvmsim.labels.site_object_labels`) and nothing else of the FMVSS site (no
A–G, guidelines, board or ground patterns).  Each site's scene renders once per viewpoint
and is cached like any scene (its objects are part of its render key).

File format (every key checked; unknown keys are errors)::

    name: my_site                 # a name: letters, digits, - and _
    title: what it is             # optional, for reports
    reference: the regulation     # optional
    position_reference: centre    # row distances to the cylinder's axis, or its near surface
    rows:
      - name: row1                # unique within the site
        z: 0.3                    # metres behind the rear-most point of the vehicle
        x: [-0.9, 0.0, {of_width: 0.5, m: 0.1}]   # lateral: metres, or of_width x width + m
        diameter: 0.3             # metres
        height: 0.8
        marking: {top_band: 0.15} # optional: the top band of this height is marked (black)

Convention
----------
Scene frame of :mod:`rvmsim.camera` (x toward the driver's side, z rearward from the
rear-most point of the bumper, metres).  Objects are numbered in file order, row by row and
left to right as written; object ``k`` is named ``<row>.<i>`` (``row1.1``), i from 1.
"""

from __future__ import annotations

import functools
import re
from importlib import resources
from pathlib import Path
from typing import Annotated, Literal

from pydantic import (Field, ValidationError, ValidationInfo, field_validator,
                      model_validator)

from .. import labels as L
from .._io import input_error_from_validation, key_lines, parse_yaml, read_text
from ..errors import RvmsimError, SceneError
from .fields import Metres, NonNegFloat, _Model


__all__ = ["SiteDefinition", "SiteRow", "Lateral", "Marking", "SiteObject", "BUNDLED_SITES",
           "DEFAULT_SITE", "load_site", "bundled_site", "site_definition", "place_objects",
           "SiteError", "is_site_file"]

#: Site definitions shipped with rvmsim: name → the regulation package holding it as
#: ``site.yaml`` (:mod:`rvmsim.regulations`, read as data).
BUNDLED_SITES: dict[str, str] = {"fmvss111": "rvmsim.regulations.fmvss111",
                                 "unr158": "rvmsim.regulations.unr158",
                                 "jp": "rvmsim.regulations.jp"}
#: The site a scene is at unless it names others.
DEFAULT_SITE = "fmvss111"

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,31}$")
_Size = Annotated[float, Field(gt=0, le=10.0)]


class SiteError(SceneError):
    """A site file that cannot be used (one line naming the file and key)."""


def _name(value: str) -> str:
    if not _NAME.match(value):
        raise ValueError(f"{value!r}: use 1-32 letters, digits, - or _ (starting with a "
                         "letter or digit)")
    return value


class Lateral(_Model):
    """A lateral position: ``of_width`` times the vehicle's width plus ``m`` metres."""

    of_width: Annotated[float, Field(ge=-5.0, le=5.0)] = 0.0
    m: Metres = 0.0

    def at(self, width_m: float) -> float:
        """x in metres for a vehicle ``width_m`` metres wide."""
        return self.m + self.of_width * width_m


class Marking(_Model):
    """How a row's cylinders are marked: a black band of ``top_band`` metres at the top, or
    (FMVSS F and G only) a vertical stripe ``vertical_stripe`` wide above a lower patch."""

    top_band: NonNegFloat = 0.0
    vertical_stripe: NonNegFloat = 0.0
    lower_patch: NonNegFloat = 0.0


class SiteRow(_Model):
    """One row of cylinders (see the module docstring)."""

    name: Annotated[str, Field(min_length=1)]
    names: list[str] | None = None
    z: Annotated[float, Field(ge=0, le=100.0)]
    x: Annotated[list[Lateral], Field(min_length=1, max_length=9)]
    diameter: _Size
    height: _Size
    marking: Marking = Marking()

    @model_validator(mode="after")
    def _check(self) -> SiteRow:
        _name(self.name)
        if self.names is not None and len(self.names) != len(self.x):
            raise ValueError(f"names: {len(self.names)} names for {len(self.x)} positions")
        if self.marking.top_band >= self.height:
            raise ValueError(f"marking.top_band ({self.marking.top_band} m) must be lower "
                             f"than the cylinder ({self.height} m)")
        return self

    @field_validator("x", mode="before")
    @classmethod
    def _metres_are_laterals(cls, value: object) -> object:
        """A plain number is ``{m: number}`` (so that a bad key of a mapping is named)."""
        if isinstance(value, list):
            return [{"m": v} if isinstance(v, (int, float)) and not isinstance(v, bool) else v
                    for v in value]
        return value

    def lateral(self, width_m: float) -> list[float]:
        """The cylinders' x, metres, for a vehicle ``width_m`` wide."""
        return [v.at(width_m) for v in self.x]


class SiteDefinition(_Model):
    """A test site: its rows of cylinders (see the module docstring)."""

    name: str
    kind: Literal["objects", "fmvss111"] = "objects"
    title: str = ""
    reference: str = ""
    position_reference: Literal["centre", "surface"] = "centre"
    rows: Annotated[list[SiteRow], Field(min_length=1)]
    #: The file it was read from (not a YAML key).
    source: str = Field(default="<site>", exclude=True)

    @field_validator("name")
    @classmethod
    def _check_name(cls, value: str) -> str:
        return _name(value)

    @field_validator("rows")
    @classmethod
    def _check_rows(cls, rows: list[SiteRow], info: ValidationInfo) -> list[SiteRow]:
        """Unique row names; at most :data:`~rvmsim.labels.MAX_SITE_OBJECTS` objects and
        top bands only, but on the FMVSS site (errors name the key ``rows``)."""
        names = [r.name for r in rows]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"row names must be unique ({', '.join(dup)} repeated)")
        if info.data.get("kind", "objects") == "objects":
            n = sum(len(r.x) for r in rows)
            if n > L.MAX_SITE_OBJECTS:
                raise ValueError(f"{n} objects: a site holds at most {L.MAX_SITE_OBJECTS}")
            for r in rows:
                if r.marking.vertical_stripe or r.marking.lower_patch:
                    raise ValueError(f"row {r.name}: vertical stripes and lower patches are "
                                     "drawn on the fmvss111 site only; use top_band")
        return rows

    def row(self, name: str) -> SiteRow:
        """The row called ``name`` (KeyError when there is none)."""
        for r in self.rows:
            if r.name == name:
                return r
        raise KeyError(name)


class SiteObject(_Model):
    """One placed test object of a site: a closed cylinder standing on the ground.

    ``index`` numbers the site's objects from 0 (its labels:
    :func:`rvmsim.labels.site_object_labels`); ``x``, ``z`` its axis (scene frame, metres);
    ``top_band`` the height of its marked top band, metres (0: none).
    """

    name: str
    row: str
    index: Annotated[int, Field(ge=0, lt=L.MAX_SITE_OBJECTS)]
    x: Metres
    z: Metres
    diameter: _Size
    height: _Size
    top_band: NonNegFloat = 0.0

    @property
    def radius(self) -> float:
        return self.diameter / 2.0

    @property
    def labels(self) -> tuple[int, int, int]:
        """(body, band, top) label ids."""
        return L.site_object_labels(self.index)


def place_objects(site: SiteDefinition, width_m: float) -> tuple[SiteObject, ...]:
    """The site's objects placed behind a vehicle ``width_m`` metres wide.

    Convention
    ----------
    ``z`` of a row is to the cylinder's axis (``position_reference: centre``) or to its
    surface nearest the car (``surface``: the axis lies a radius further rearward).
    """
    out: list[SiteObject] = []
    for row in site.rows:
        z = row.z + (row.diameter / 2.0 if site.position_reference == "surface" else 0.0)
        for i, x in enumerate(row.lateral(width_m)):
            name = row.names[i] if row.names else f"{row.name}.{i + 1}"
            out.append(SiteObject(name=name, row=row.name, index=len(out), x=x, z=z,
                                  diameter=row.diameter, height=row.height,
                                  top_band=row.marking.top_band))
    return tuple(out)


def _definition(text: str, source: str) -> SiteDefinition:
    data = parse_yaml(text, source, SiteError)
    if not isinstance(data, dict):
        raise SiteError(source, "", "a site file must be a YAML mapping (key: value)")
    try:
        return SiteDefinition.model_validate({**data, "source": source})
    except ValidationError as err:
        raise input_error_from_validation(err, source, key_lines(text), SiteError,
                                          frozenset()) from None


def load_site(path: str | Path) -> SiteDefinition:
    """Read and check a site file.

    Raises
    ------
    SiteError
        Unreadable file, malformed YAML, or a bad key (one line naming the file and key).
    """
    path = Path(path)
    return _definition(read_text(path, SiteError), str(path))


@functools.cache
def bundled_site(name: str) -> SiteDefinition:
    """A site shipped with rvmsim (:data:`BUNDLED_SITES`).

    Raises
    ------
    RvmsimError
        An unknown name (one line listing the known ones).
    """
    if name not in BUNDLED_SITES:
        raise RvmsimError(f"site {name!r}: unknown (bundled sites: "
                          f"{', '.join(BUNDLED_SITES)}; or give a site file)")
    text = resources.files(BUNDLED_SITES[name]).joinpath("site.yaml").read_text(
        encoding="utf-8")
    return _definition(text, f"<bundled site {name}>")


def is_site_file(entry: str) -> bool:
    """Whether a site entry (a scene's ``sites:``, ``--site``, a market's SITE) names a file
    (``.yaml``/``.yml``, or a path with a folder) rather than a bundled site."""
    return entry.lower().endswith((".yaml", ".yml")) or "/" in entry


def site_definition(entry: str, base_dir: str | Path = ".") -> SiteDefinition:
    """A site from a name (bundled) or a file path (:func:`is_site_file`, relative to
    ``base_dir``, the folder of the file that names it)."""
    if entry in BUNDLED_SITES:
        return bundled_site(entry)
    if is_site_file(entry):
        p = Path(entry).expanduser()
        return load_site(p if p.is_absolute() else Path(base_dir) / p)
    return bundled_site(entry)  # raises: unknown name
