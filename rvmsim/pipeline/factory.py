"""One factory for every evaluator: a candidate's ECs on one fisheye image, or one setting's
ECs on a batch of images (variation samples today, cars off the line next).

:func:`make_evaluator` is the only place an evaluator is chosen.  It takes what is judged
and the criteria, and picks the path from what the criteria declare:

==================  ==========================================================================
source              path
==================  ==========================================================================
one image           ``windowed`` (:class:`rvmsim.pipeline.CandidateEvaluator`): the map's
                    node grid, only the windows of the label groups the ECs declare; built
                    once per image, for many candidates (tuning).
a batch of images   ``rvm-pixels``: one map per setting, each image's labels only at the
                    fisheye pixels the RVM image shows (:class:`RvmPixels`) — when no EC
                    reads the scene (:attr:`rvmsim.criteria.Criteria.uses_scene`); else
                    ``full``: each image's whole fisheye labels through the full path.
==================  ==========================================================================

A sequence of members (each a fisheye label image, optionally with its own ``criteria``)
gets an :class:`ImagesEvaluator`: every member's evaluator as above, those that can share a
candidate's map judged together.

``path="full"`` asks for the full path (:func:`rvmsim.pipeline.evaluate_rvm_labels` on the
whole remapped label image, what ``rvmsim evaluate`` measures) whatever the criteria: the
reference the fast paths are tested against, EC value for EC value.

Criteria whose ECs read the scene (1-5, 1-6, 6-1) are refused for images that carry no
scene: those ECs would come out "not measured" and fail every candidate.

Every evaluator judges at the RVM image of record (:mod:`rvmsim.criteria.record`: the
display output, default 1280 × 720).  Asked to measure at another size, it converts the
pixel-unit values to pixels of record and measures again at the size of record every
candidate (or image) that passes or fails only near its limits: a pass is a pass on the
display, whatever size the search measures at (:class:`rvmsim.pipeline.RecordRule`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import overload

from ..criteria import Criteria, default_criteria, record_size
from ..isp import OutputSpec
from ..scene import Scene
from .batched import ImagesEvaluator
from .candidate import CandidateEvaluator
from .evaluators import (EvaluationPath, FisheyeLabels, FisheyeSet, FullEvaluator,
                         ImageEvaluator, RecordEvaluator, SetEvaluator)

__all__ = ["make_evaluator", "record_output"]


@overload
def make_evaluator(source: FisheyeSet, output: OutputSpec, criteria: Criteria | None = ...,
                   *, path: EvaluationPath | str | None = ...,
                   record: OutputSpec | None = ...) -> SetEvaluator: ...


@overload
def make_evaluator(source: FisheyeLabels, output: OutputSpec, criteria: Criteria | None = ...,
                   *, path: EvaluationPath | str | None = ...,
                   record: OutputSpec | None = ...) -> ImageEvaluator: ...


@overload
def make_evaluator(source: Sequence[FisheyeLabels], output: OutputSpec,
                   criteria: Criteria | None = ..., *, path: EvaluationPath | str | None = ...,
                   record: OutputSpec | None = ...) -> ImagesEvaluator: ...


def make_evaluator(source: FisheyeLabels | FisheyeSet | Sequence[FisheyeLabels],
                   output: OutputSpec, criteria: Criteria | None = None, *,
                   path: EvaluationPath | str | None = None,
                   record: OutputSpec | None = None
                   ) -> ImageEvaluator | SetEvaluator | ImagesEvaluator:
    """The evaluator of ``criteria`` on ``source``, on the path the criteria allow.

    Parameters
    ----------
    source : FisheyeLabels, FisheyeSet or sequence of FisheyeLabels
        One fisheye label image (e.g. :class:`rvmsim.render.FisheyeImages`), judged for many
        candidates; a batch of images judged for one setting at a time; or the members of a
        multi-member run (:class:`rvmsim.tune.Member`), each judged by its own ``criteria``
        when it has them (else ``criteria``), for many candidates.
    output : OutputSpec
        The RVM image size (px) and mirroring the ECs are measured at (the search size).
    criteria : Criteria, optional
        Default: the paper's (:func:`rvmsim.criteria.default_criteria`).
    path : EvaluationPath or str, optional
        Default: the fastest exact path (the module docstring's table); ``"full"`` for the
        reference.  One image takes ``windowed`` or ``full``; a batch ``rvm-pixels`` (only
        when no EC reads the scene) or ``full``.
    record : OutputSpec, optional
        The RVM image of record the verdicts refer to (default: :func:`record_output` of the
        criteria and ``source``'s scene, mirrored as ``output``).  When its size differs from
        ``output``'s, the evaluator converts and re-measures (the module docstring).

    Returns
    -------
    ImageEvaluator, SetEvaluator or ImagesEvaluator

    Raises
    ------
    ValueError
        The criteria read the scene but ``source`` carries none; or ``path`` does not fit.
    """
    crit = criteria if criteria is not None else default_criteria()
    chosen = None if path is None else EvaluationPath(path)
    if isinstance(source, Sequence) and not isinstance(source, FisheyeSet):  # members
        return ImagesEvaluator([make_evaluator(m, output, getattr(m, "criteria", None) or crit,
                                               path=path, record=record) for m in source])
    if crit.uses_scene and source.scene is None:
        ids = ", ".join(ec.id for ec in crit.ecs if ec.uses_scene)
        raise ValueError(f"criteria {crit.name!r}: ECs {ids} read the scene, but the images "
                         "carry none")
    if isinstance(source, FisheyeSet):
        chosen = chosen or (EvaluationPath.FULL if crit.uses_scene else EvaluationPath.RVM_PIXELS)
        if chosen is EvaluationPath.WINDOWED or (chosen is EvaluationPath.RVM_PIXELS
                                                 and crit.uses_scene):
            raise ValueError(f"a batch of images cannot take the {chosen.value} path"
                             + (" with ECs that read the scene" if crit.uses_scene else ""))
        rec = record or record_output(crit, source.scene, output.mirror)
        return SetEvaluator(source, output, crit, chosen, rec)
    chosen = chosen or EvaluationPath.WINDOWED
    if chosen is EvaluationPath.RVM_PIXELS:
        raise ValueError("one image takes the windowed or the full path")
    rec = record or record_output(crit, source.scene, output.mirror)

    def at(out: OutputSpec) -> ImageEvaluator:
        if chosen is EvaluationPath.FULL:
            return FullEvaluator(source, out, crit)
        return CandidateEvaluator(source.labels, out, crit, scene=source.scene,
                                  camera=source.camera)

    if (rec.width, rec.height) == (output.width, output.height):
        return at(output)
    return RecordEvaluator(at(output), at(OutputSpec(rec.width, rec.height, output.mirror)))


def record_output(criteria: Criteria, scene: Scene | None = None, mirror: bool = True
                  ) -> OutputSpec:
    """The RVM image of record (:func:`rvmsim.criteria.record_size`: the scene's or criteria
    file's ``display.rvm_image_px``, default 1280 × 720), mirrored as given."""
    w, h = record_size(criteria, scene)
    return OutputSpec(w, h, mirror)
