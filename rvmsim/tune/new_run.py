"""A new tuning run's settings, scenes and criteria from its request, every input checked
before anything is written.

The request's kind (:class:`~rvmsim.tune.Shared`, :class:`~rvmsim.tune.Robust`,
:class:`~rvmsim.tune.Markets`; none: one scene, or several shared) has checked its own values
when it was made; here each kind is checked against the scenes, in one function per kind, and
recorded (:class:`rvmsim.runs.RunKind`):

- one scene: its criteria (the ECs it supports), its fingerprint, the size of record;
- shared: at least two scenes, with cameras of one sensor size;
- markets: no criteria of the request's own (each market has its own); one sensor size;
- robust (over one scene or shared): the variations fingerprinted, and a compensation
  model's law registered and its load state in every variation.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

from ..compensation import measured_load_index
from ..criteria import Criteria, check_supported, criteria_reference, load_criteria, record_size
from ..errors import RvmsimError
from ..markets import market_criteria, parse_markets
from ..percar import check_law
from ..render import scene_key
from ..runs.records import RobustRecord, RunKind, RunSettings, SceneRef
from ..scene import Scene, load_scene
from ..search.config import TuningConfig
from ..search.strategies import check_seed
from .members import check_cameras
from .requests import Markets, Robust, SceneArg, Shared, TuneRequest
from .robust import run_variations, variation_key

__all__ = ["new_run_settings", "load_shared_scenes"]


def new_run_settings(r: TuneRequest) -> tuple[RunSettings, list[Scene], Criteria]:
    """A new run's settings, scenes and criteria from request ``r`` (see the module
    docstring).

    Raises
    ------
    RvmsimError
        One line naming the input: a bad seed or budget, scene, criteria or config, or a
        kind the scenes cannot have.
    """
    check_seed(r.seed)
    if r.budget is not None and (not isinstance(r.budget, int) or isinstance(r.budget, bool)
                                 or r.budget < 1):
        raise RvmsimError(f"--budget {r.budget!r}: give a whole number of at least 1")
    kind = r.kind
    if isinstance(kind, Markets):  # one parameter set for every market (and scene)
        return _markets(r, kind)
    if isinstance(kind, Shared) or r.shared:
        settings, scenes, crit = _shared(r, kind.aggregate if isinstance(kind, Shared) else "min")
    else:
        settings, scenes, crit = _single(r)
    if isinstance(kind, Robust):
        settings = _made_robust(settings, scenes, kind)
    return settings, scenes, crit


def load_shared_scenes(scenes: Sequence[SceneArg]) -> list[tuple[str, Scene]]:
    """The scenes of a shared run as (recorded file, Scene): at least two, with cameras of
    one sensor size.

    Raises
    ------
    RvmsimError
        One line: fewer than two scenes, a bad scene file, or cameras that differ.
    """
    if len(scenes) < 2:
        raise RvmsimError(f"--shared: give at least two scenes (got {len(scenes)}); tune one "
                          "scene without --shared")
    out = [_loaded(s, None) for s in scenes]
    check_cameras([(f"{rec} ({sc.name})", sc.fisheye_camera()) for rec, sc in out])
    return out


def _single(r: TuneRequest) -> tuple[RunSettings, list[Scene], Criteria]:
    """One scene: its criteria (each EC it cannot support refused or, with
    ``only_supported``, left out), its scene loaded and fingerprinted, the config at the
    size of record."""
    crit = r.criteria if r.criteria is not None else load_criteria(r.criteria_file)
    recorded, sc = _loaded(r.scenes[0], r.scene_file)
    crit, left_out = _supported(crit, [(recorded, sc)], r.only_supported)
    record = record_size(crit, sc)
    return (_settings(r, [(recorded, sc)], record, RunKind(), r.criteria_file,
                      left_out, shared=False), [sc], crit)


def _shared(r: TuneRequest, aggregate: str) -> tuple[RunSettings, list[Scene], Criteria]:
    """Several scenes, one parameter set: every scene loaded (one sensor size), the
    criteria every scene supports, the size of record of the first scene."""
    crit = r.criteria if r.criteria is not None else load_criteria(r.criteria_file)
    scenes = load_shared_scenes(r.scenes)
    crit, left_out = _supported(crit, scenes, r.only_supported)
    record = record_size(crit, scenes[0][1])
    return (_settings(r, scenes, record, RunKind(aggregate), r.criteria_file, left_out),
            [sc for _, sc in scenes], crit)


def _markets(r: TuneRequest, kind: Markets) -> tuple[RunSettings, list[Scene], Criteria]:
    """Every scene in every market: no criteria of the request's own, one sensor size, the
    first market's criteria and size of record."""
    if r.criteria is not None or r.criteria_file is not None:  # each market has its own
        raise RvmsimError("--criteria: give no criteria with --markets (a market may be "
                          "SITE:CRITERIA with your criteria file)")
    markets = parse_markets(kind.markets)
    loaded = [_loaded(s, r.scene_file) for s in r.scenes]
    check_cameras([(f"{rec} ({sc.name})", sc.fisheye_camera()) for rec, sc in loaded])
    crit = market_criteria(markets[0])
    record = record_size(crit, loaded[0][1])
    return (_settings(r, loaded, record,
                      RunKind(kind.aggregate, markets=tuple(m.spec for m in markets)), None, ()),
            [sc for _, sc in loaded], crit)


def _made_robust(settings: RunSettings, scenes: Sequence[Scene], kind: Robust) -> RunSettings:
    """``settings`` (a single or shared run's) made robust: the variations checked and
    fingerprinted, and the compensation model recorded (its law registered, its load state
    checked against every variation)."""
    vfile = None if kind.variation_file is None else str(Path(kind.variation_file).resolve())
    variations = run_variations(scenes, vfile)
    model = kind.compensation
    if model is not None:
        check_law(model)
        for v in variations:
            measured_load_index(model, [s.name for s in v.load_states])
    record = RobustRecord(kind.samples, vfile, variation_key(variations),
                          None if model is None else model.as_dict())
    return dataclasses.replace(settings, kind=RunKind(kind.aggregate, record))


def _settings(r: TuneRequest, scenes: Sequence[tuple[str, Scene]], record: tuple[int, int],
              kind: RunKind, criteria_file: str | Path | None, left_out: tuple[str, ...], *,
              shared: bool = True) -> RunSettings:
    """The settings of a new run over ``scenes`` (the first is also ``scene``; ``shared``:
    every one recorded in ``scenes``), judged at ``record`` (W, H px)."""
    refs = tuple(SceneRef(str(Path(rec).resolve()), scene_key(sc), sc.name)
                 for rec, sc in scenes)
    return RunSettings(
        scene=refs[0].scene, scene_key=refs[0].scene_key, vehicle=refs[0].vehicle,
        strategy=r.strategy, seed=r.seed, budget=r.budget,
        criteria_file=None if criteria_file is None else criteria_reference(criteria_file),
        config=(r.config or TuningConfig()).at_record(record), scenes=refs if shared else (),
        kind=kind, judged_at=record, left_out=left_out)


def _loaded(scene: SceneArg, scene_file: str | Path | None) -> tuple[str, Scene]:
    """(the file recorded for ``scene``, the Scene): a file is loaded and recorded as given;
    a loaded Scene is recorded by ``scene_file``, else by its own source (else its name)."""
    if isinstance(scene, Scene):
        return str(scene_file or scene.source or scene.name), scene
    return str(scene), load_scene(scene)


def _supported(crit: Criteria, scenes: Sequence[tuple[str, Scene]], only_supported: bool
               ) -> tuple[Criteria, tuple[str, ...]]:
    """The criteria every scene supports (:func:`rvmsim.criteria.check_supported`: refused
    before any work unless ``only_supported``) and the ECs that left out."""
    out = crit
    for recorded, sc in scenes:
        out = check_supported(sc, out, recorded, only_supported=only_supported)
    return out, tuple(k for k in crit.ids if crit.items[k].enabled and not out.items[k].enabled)
