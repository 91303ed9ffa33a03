"""Capture files validated one after another (``rvmsim validate --capture …``).

:func:`rvmsim.pose.capture_files` turns the paths given (files, or folders of them) into capture files;
:func:`validate_captures` reads every capture first (one that cannot be read is refused
before any work), then validates each into its own output folder and returns one
:class:`CaptureOutcome` per capture: its validation, or the error that stopped it (a capture
that cannot be validated, or whose outputs cannot be written, is that capture's row, and the
others still run).  The outputs of a finished validation (its JSON and page) are
written by the caller's ``write_outputs`` (:func:`rvmsim.report.write_validation_outputs`);
a failed one leaves its pictures (:func:`~.outputs.write_pictures`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import RvmsimError
from ..storage import os_error_text, staged_folder
from .failure import ValidationFailure
from .validation import ValidationSettings, validate
from .verdict import Validation
from ..pose import check_captures, load_capture
from .outputs import write_pictures

if TYPE_CHECKING:
    from ..scene import Scene

__all__ = ["CaptureOutcome", "validate_captures"]

@dataclass(frozen=True)
class CaptureOutcome:
    """One capture's validation, or the error that stopped it.

    Attributes
    ----------
    capture : str
        The capture's file.
    out_dir : Path
        Where its outputs went.
    result : Validation or None
        None when the validation stopped with an error.
    error : str
        The error's one-line message ("" when it finished).
    step : str
        The failed step: ``detection``, ``correspondence``, ``pose fit`` (an error),
        ``check: …`` (a failed verdict: the checks that failed), ``error`` (another error),
        "" (passed).
    images : dict of str to (H, W, 3) uint8
        The failure's pictures (when ``result`` is None).
    written : tuple of Path
        The files written for a finished validation (``write_outputs``' list).
    """

    capture: str
    out_dir: Path
    result: Validation | None
    error: str = ""
    step: str = ""
    images: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)
    written: tuple[Path, ...] = field(default=(), repr=False, compare=False)

    @property
    def verdict(self) -> str:
        if self.result is None:
            return "ERROR"
        return "PASS" if self.result.passed else "FAIL"

    @property
    def message(self) -> str:
        """The error as one line for the user ("" when the validation finished): a failed
        step also says where its pictures are."""
        if self.result is not None:
            return ""
        return self.error if self.step == "error" else f"{self.error}; pictures in {self.out_dir}"

    def row(self) -> dict[str, Any]:
        """The summary table's row (numbers px, mm, degrees; None where not measured)."""
        r = self.result
        c = None if r is None else r.correction
        return {
            "capture": self.capture, "verdict": self.verdict, "step_failed": self.step,
            "inliers": None if r is None else r.n_inliers,
            "predicted": None if r is None else r.n_predicted,
            "rms_before_px": None if r is None else r.rms_before_px,
            "rms_after_px": None if r is None else r.rms_after_px,
            "d_position_mm": None if c is None else c.d_position_norm_mm,
            "max_d_angle_deg": None if c is None else c.max_d_angle_deg,
            "error": self.error, "out_dir": str(self.out_dir),
        }


def validate_captures(
    scene: Scene,
    captures: Sequence[Path],
    folders: Sequence[Path],
    write_outputs: Callable[[Validation, Path], list[Path]],
    settings: ValidationSettings = ValidationSettings(),
    *,
    progress: bool = False,
    on_outcome: Callable[[CaptureOutcome], None] | None = None,
) -> list[CaptureOutcome]:
    """Validate ``scene`` against each capture file, one after another.

    Parameters
    ----------
    scene : Scene
    captures : sequence of Path
        The capture files (:func:`capture_files`).
    folders : sequence of Path
        Each capture's output folder (one capture: the output folder itself; several:
        :func:`capture_folders`).
    write_outputs : callable
        ``write_outputs(validation, folder)`` writes a finished validation's files and
        returns them (:func:`rvmsim.report.write_validation_outputs`).
    settings : ValidationSettings
        How each capture is judged (:func:`~.validation.validate`).
    progress : bool
        Progress bars while rendering; the synthetic frame comes through the render cache.
    on_outcome : callable, optional
        Called with each capture's outcome as it is known (to report it at once).

    Returns
    -------
    list of CaptureOutcome
        One per capture, in order.  A capture that cannot be validated, or whose outputs
        cannot be written, is an ``ERROR`` outcome with the one-line message (a failed
        step's pictures are written into its folder first); nothing is raised for it.

    Raises
    ------
    RvmsimError
        Before any work (no render, no search, nothing written): a capture that is
        missing, unreadable, corrupt, blank or of another size than the camera's
        (:func:`~.capture.check_captures`), naming it.
    """

    if len(folders) != len(captures):
        raise ValueError(f"{len(captures)} captures but {len(folders)} output folders")
    check_captures(captures, scene.fisheye_camera())
    def one(capture_file: Path, out: Path) -> CaptureOutcome:
        name = str(capture_file)
        try:
            capture = load_capture(capture_file, scene.fisheye_camera())
            try:
                result = validate(scene, capture, settings, use_cache=True,
                                  capture_name=name, progress=progress)
            except ValidationFailure as fail:
                with staged_folder(out) as stage:  # moved in when all are written
                    write_pictures(fail.images, stage)
                return CaptureOutcome(name, out, None, str(fail), fail.step, fail.images)
            written = write_outputs(result, out)
        except RvmsimError as err:
            return CaptureOutcome(name, out, None, str(err), "error")
        except OSError as err:
            return CaptureOutcome(name, out, None, f"{err.filename or out}: {os_error_text(err)}",
                                  "error")
        failed = [c.name for c in result.checks if not c.passed]
        return CaptureOutcome(name, out, result, step="check: " + ", ".join(failed) if failed
                              else "", written=tuple(written))

    outcomes = []
    for capture_file, out in zip(captures, folders, strict=True):
        outcomes.append(one(capture_file, out))
        if on_outcome is not None:
            on_outcome(outcomes[-1])
    return outcomes
