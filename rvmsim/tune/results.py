"""What every tuning run writes at its end: ``top/`` (the diverse top-M) and ``best/`` (the
best candidate's pictures and EC table at the RVM image of record), and how a run is removed
(``tune --force``)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from .._io import write_png
from ..errors import RvmsimError
from ..isp import params_to_dict
from ..pipeline import evaluate_params, record_output, write_frame
from ..runs.folder import RUN_DB, RUN_JSON, write_top_files
from ..runs.store import RunStore

if TYPE_CHECKING:
    from ..criteria import Criteria, EcResult
    from ..render import FisheyeImages
    from ..scene import Scene
    from ..search.config import TuningConfig

__all__ = ["write_results", "remove_run"]


def remove_run(run_dir: str | Path) -> None:
    """Delete the run in ``run_dir``: its store, run.json, ``top/``, ``best/`` and its
    report (what ``tune --force`` does, holding the run's lock, once the new run's inputs
    have all loaded), so that nothing of it mixes with a new run there."""
    run_dir = Path(run_dir)
    for name in (RUN_DB, f"{RUN_DB}-wal", f"{RUN_DB}-shm", RUN_JSON, "report.html"):
        (run_dir / name).unlink(missing_ok=True)
    for name in ("top", "best"):
        if (run_dir / name).is_dir():
            shutil.rmtree(run_dir / name)


def write_results(run_dir: Path, store: RunStore, scene: Scene, images: FisheyeImages,
                  config: TuningConfig, criteria: Criteria) -> EcResult | None:
    """top/: the diverse top-M (:func:`rvmsim.runs.write_top_files`: ``rank_K.yaml`` and
    ``candidates.json``), and best/ (rank 1, the best trial): RVM image, annotated ECs and EC
    table at the RVM image of record (:func:`rvmsim.pipeline.record_output`), the verdict the
    run stored.  Returns the best candidate's ECs at the RVM image of record (None: no
    trials)."""

    settings = store.settings()
    if settings is None:
        raise RvmsimError(f"{store.path}: no run settings recorded")  # tune() writes them first
    cands = write_top_files(run_dir, store, settings, scene.name, criteria)
    if not cands:
        return None
    top = store.trials_at([cands[0].trial])
    out = config.output_spec()
    record = record_output(criteria, scene, out.mirror)
    best = top[0]
    frame = evaluate_params(images, best.params, record, criteria)
    write_frame(frame, run_dir / "best")
    (run_dir / "best" / "ec.json").write_text(json.dumps(
        {"vehicle": scene.name, "trial": best.idx, **frame.ec.as_dict(),
         "judged_at": [record.width, record.height],
         "isp": params_to_dict(best.params, out, judged_at=record)}, indent=2))
    (run_dir / "best" / "ec_table.txt").write_text(frame.ec.table() + "\n")
    # The display's picture (the view is defined in normalised coordinates, so only the pixel
    # count differs from the search size's; aspect ratios differing crop or extend it).
    write_png(run_dir / "best" / "rvm_display.png", frame.color)
    return frame.ec
