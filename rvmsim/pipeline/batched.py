"""One candidate judged on several fisheye label images with one map: the evaluation of a
multi-member tuning run (robust tuning's nominal image and variation samples, shared
tuning's vehicles of one sensor size).

:class:`ImagesEvaluator` takes the members' evaluators as :func:`make_evaluator` made them
and groups those that can share a candidate's map: windowed evaluators
(:class:`rvmsim.pipeline.CandidateEvaluator`) of one fisheye size and RVM output, judged
together by a :class:`rvmsim.pipeline.CandidateBatch`; and evaluators measuring at a search
size for a size of record (:class:`RecordEvaluator`), whose search measurements are batched
the same way and whose undecided members are measured at the size of record in one batch
too.  Any other evaluator is asked on its own.  The values are those of each member's own
evaluator, value for value.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..isp import IspParams
from .candidate import CandidateEvaluator
from .candidate_batch import CandidateBatch
from .evaluators import ImageEvaluator, RecordEvaluator

__all__ = ["ImagesEvaluator"]


@dataclass(frozen=True)
class _Group:
    """Members judged together: ``search`` batches their evaluators (or the search parts of
    their :class:`RecordEvaluator`), ``record`` the parts of record (None: no such part)."""

    members: tuple[int, ...]
    search: CandidateBatch
    record: CandidateBatch | None


def _key(ev: ImageEvaluator) -> tuple[object, ...] | None:
    """Evaluators with equal keys share a batch (None: evaluated alone)."""
    if isinstance(ev, CandidateEvaluator) and ev.windowed:
        return ("one", ev.input_size, ev.output)
    if (isinstance(ev, RecordEvaluator) and isinstance(ev.search, CandidateEvaluator)
            and isinstance(ev.record, CandidateEvaluator) and ev.search.windowed
            and ev.record.windowed):
        return ("record", ev.search.input_size, ev.search.output, ev.record.output)
    return None


class ImagesEvaluator:
    """The values of one candidate on every member's image (see the module docstring).

    Parameters
    ----------
    evaluators : sequence of ImageEvaluator
        One per member (:func:`make_evaluator`), each with its own criteria.

    Notes
    -----
    Picklable (it goes to tuning's worker processes).
    """

    def __init__(self, evaluators: Sequence[ImageEvaluator]):
        self.evaluators = list(evaluators)
        self._alone: list[int] = []
        #: The batches, made on first use (in the process that evaluates: not pickled).
        self._groups: list[_Group] | None = None

    def __getstate__(self) -> dict[str, object]:
        return {"evaluators": self.evaluators}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__init__(state["evaluators"])  # type: ignore[misc]

    def __len__(self) -> int:
        return len(self.evaluators)

    def _grouped(self) -> list[_Group]:
        if self._groups is None:
            by_key: dict[tuple[object, ...], list[int]] = {}
            self._alone = []
            for m, ev in enumerate(self.evaluators):
                key = _key(ev)
                if key is None:
                    self._alone.append(m)
                else:
                    by_key.setdefault(key, []).append(m)
            self._groups = [self._group(tuple(ms)) for ms in by_key.values()]
        return self._groups

    def _group(self, members: tuple[int, ...]) -> _Group:
        evs = [self.evaluators[m] for m in members]
        if isinstance(evs[0], RecordEvaluator):
            rec = [ev for ev in evs if isinstance(ev, RecordEvaluator)]
            return _Group(members, CandidateBatch([e.search for e in rec]),  # type: ignore[misc]
                          CandidateBatch([e.record for e in rec]))  # type: ignore[misc]
        return _Group(members, CandidateBatch(evs), None)  # type: ignore[arg-type]

    def values(self, params: IspParams) -> list[np.ndarray]:
        """Each member's values of ``params`` ((k_m,) in its criteria's ``ids`` order, NaN
        where not measured), as its evaluator's ``values`` gives them."""
        out: list[np.ndarray | None] = [None] * len(self.evaluators)
        for g in self._grouped():
            found = g.search.values(params)
            if g.record is None:
                for m, v in zip(g.members, found):
                    out[m] = v
                continue
            undecided = []
            for k, (m, v) in enumerate(zip(g.members, found)):
                ev = self.evaluators[m]
                assert isinstance(ev, RecordEvaluator)
                out[m] = ev.decided_values(v)
                if out[m] is None:
                    undecided.append(k)
            if undecided:
                for k, v in zip(undecided, g.record.values(params, undecided)):
                    out[g.members[k]] = v
        for m in self._alone:
            out[m] = self.evaluators[m].values(params)
        done = [v for v in out if v is not None]
        assert len(done) == len(out)  # every member is in a group or alone
        return done
