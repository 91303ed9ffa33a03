"""The sign-off sheet of an ISP setting: one self-contained HTML page and its PDF, for a
reviewer to sign (``rvmsim signoff RUN --out DIR``).

It gathers, for the best candidate (rank 1) of a tuning run:

- the setting: its 14 values, its params file and that file's SHA-256 (the run's
  ``top/rank_1.yaml`` when it holds exactly these values, else ``params.yaml`` written into
  the output folder; the hash is of exactly the file named);
- the input files (scene, meshes, criteria, variation, compensation, and the result files
  read) with their SHA-256, flagging any whose hash differs from the robustness run's record;
- the tool: version, commit of its source checkout, date (UTC), machine;
- every EC at the display output of record (:func:`_record_output`) on the full evaluation
  path, with value, limit, margin and its annotated picture;
- the car's parking guidelines through the setting (:mod:`.guidelines`): their picture, the
  steering angles covered and the SHA-256 of the ECU table, written into the output folder
  as ``guidelines.bin`` (or the reason there are none);
- the yield before and after compensation, per EC and per load state
  (``--robustness DIR``), or a red "robustness not run" line;
- the validation against a real capture (``--validation DIR``) and the end-of-line
  record (``--eol DIR``), or that they were not given;
- each failing sample with the command that reproduces it;
- a signature block.

``signoff.json`` beside the page records the figures (the run report reads the yield from
it).  The PDF is printed from the page by headless Chromium (Playwright driving Debian's
``chromium``).
"""

from __future__ import annotations

import dataclasses
import json
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._progress import progress_bar
from ..criteria import annotate, bundled_criteria_text
from ..criteria.closeup import closeup, text_px_for_print
from ..errors import RvmsimError
from ..isp import params_to_dict, process
from ..pipeline import make_evaluator, record_output
from ..runs import rank_text, top_file
from ..storage import json_default, staged_folder, write_text
from ..tune.markets import load_markets
from .market_rows import all_markets_pass, markets_rows, markets_verdict_text
from .pdf import find_chromium, print_pdf
from .provenance import FileRecord, file_record, provenance, scene_records
from .guidelines import GUIDELINE_TABLE, guideline_figures
from .records import (SIGNOFF_JSON, EolRecord, RobustnessRecord, ValidationRecord, load_eol,
                      load_robustness, load_validation, same_setting)
from .run import _load_run, _Run
from .setting import SettingRecord
from .signoff_page import signoff_html
from .signoff_summary import (COMPENSATION_ROLE, Check, SignoffContent, failure_groups,
                              sheet_passes)

if TYPE_CHECKING:
    from ..criteria import Criteria, EcResult
    from ..isp import IspParams, OutputSpec
    from ..render import FisheyeImages
    from ..scene import Scene

__all__ = ["signoff", "SignoffResult", "find_chromium", "print_pdf", "PARAMS_FILE",
           "other_setting"]

#: The params file written into the output folder when the run has none for its best.
PARAMS_FILE = "params.yaml"

#: Each EC's close-up on the sheet: its width in px, the width it prints at (mm: two to a
#: row of an A4 page's 182 mm column) and its labels' cap height on paper (mm).
EC_PICTURE_PX = 800
EC_PICTURE_MM = 88.0
EC_TEXT_MM = 2.8


@dataclass(frozen=True)
class SignoffResult:
    """What :func:`signoff` wrote: the page, its PDF (None: not asked for), signoff.json,
    the params file named on the page with its SHA-256, and the headline figures."""

    html: Path
    pdf: Path | None
    json: Path
    params_file: Path
    params_sha256: str
    nominal_passed: bool
    yield_: float | None
    #: A markets run: whether its best setting passes every market (None: not a markets
    #: run); :attr:`markets_text` says so in words.
    markets_passed: bool | None = None
    markets_text: str | None = None
    #: Why a given folder is not of this setting or vehicle (``allow_other_setting``).
    other_setting: tuple[str, ...] = ()
    #: What the sheet judged (:func:`~rvmsim.report.signoff_summary.verdict_checks`), and
    #: whether none of it fails: the sheet's verdict (``rvmsim signoff`` exits 1 if not).
    checks: tuple[Check, ...] = ()
    passed: bool = True
    #: The guidelines' ECU table written beside the page and its SHA-256 (None: no
    #: guidelines, :attr:`guidelines_text` says why).
    guidelines_file: Path | None = None
    guidelines_sha256: str | None = None
    guidelines_text: str = ""


def _record_output(criteria: Criteria, scene: Scene, output: OutputSpec) -> OutputSpec:
    """The RVM output the ECs of record are judged at (:func:`rvmsim.pipeline.record_output`:
    the scene's or criteria's ``display.rvm_image_px``, default 1280 × 720), mirrored as the
    tuning output is."""

    return record_output(criteria, scene, output.mirror)


def _record_ecs(images: FisheyeImages, params: IspParams, output: OutputSpec,
                criteria: Criteria) -> tuple[EcResult, np.ndarray, np.ndarray,
                                             dict[str, np.ndarray]]:
    """The ECs at ``output`` on the full path, the RVM picture, every EC drawn on it, and
    each EC's close-up (:func:`rvmsim.criteria.closeup.closeup`: what it measures,
    :data:`EC_PICTURE_PX` wide, labels :data:`EC_TEXT_MM` tall at :data:`EC_PICTURE_MM`)."""

    ec = make_evaluator(images, output, criteria, path="full")(params)
    color, labels = process(images.color, images.labels, params, output)
    assert color is not None and labels is not None
    text_px = text_px_for_print(EC_PICTURE_PX, EC_PICTURE_MM, EC_TEXT_MM)
    each = {}
    for k, item in enumerate(ec.items):
        if not item.enabled:
            continue
        one = dataclasses.replace(ec, items=(item,), definitions=(
            (ec.definitions[k],) if ec.definitions else ()))
        each[item.id] = closeup(color, labels, one, width_px=EC_PICTURE_PX,
                                text_px=text_px).image
    return ec, color, annotate(color, labels, ec), each


def _params_record(r: _Run, out: Path, stage: Path) -> FileRecord:
    """The params file of the setting: the run's ``top/rank_1.yaml`` when it holds rank 1's
    values and output, else :data:`PARAMS_FILE` written into ``stage`` (the staging folder
    of ``out``, where the record says it is)."""

    best = r.top[0]
    searched = r.config.output_spec()  # a params file's output: the size the run searched at
    ranked = top_file(r.run_dir, 1, best.params, searched)
    if ranked is not None:
        return file_record("params", ranked)
    path = stage / PARAMS_FILE  # absent or stale: the sign-off writes its own
    write_text(path, rank_text(best, 1, searched, r.scene.name, judged_at=r.output))
    return dataclasses.replace(file_record("params", path),
                               path=str((out / PARAMS_FILE).resolve()))


def _dedupe(records: list[FileRecord]) -> list[FileRecord]:
    seen: set[str] = set()
    out = []
    for rec in records:
        if rec.path not in seen:
            seen.add(rec.path)
            out.append(rec)
    return out


def _criteria_record(path: Path | str | None, role: str = "criteria") -> list[FileRecord]:
    if path is None:
        return [FileRecord(role, "built-in (the paper's thresholds)", None, "no file")]
    if bundled_criteria_text(str(path)) is not None:
        return [FileRecord(role, str(path), None, "bundled criteria set")]
    return [file_record(role, path)]


def _robustness_files(rob: RobustnessRecord) -> tuple[list[FileRecord], list[str]]:
    """The robustness run's input files hashed now, and those whose hash differs from the
    one it recorded."""
    recorded = rob.inputs.get("files")
    if not isinstance(recorded, list):  # a robustness.json of an earlier rvmsim
        return scene_records(str(rob.doc["scene"]), "scene (robustness)"), []
    now, changed = [], []
    for rec in recorded:
        if not isinstance(rec, dict) or not rec.get("sha256"):
            continue
        cur = file_record(f"{rec.get('role', 'file')} (robustness)", str(rec.get("path")))
        now.append(cur)
        if cur.sha256 != rec.get("sha256"):
            changed.append(cur.path)
    return now, changed


def _files(r: _Run, setting: SettingRecord, rob: RobustnessRecord | None,
           val: ValidationRecord | None, eol: EolRecord | None) -> tuple[list[FileRecord],
                                                                       list[str]]:
    """Every input file with its SHA-256 (see the module docstring), and the changed ones."""
    files = [setting.file, *scene_records(r.scene_file), *_criteria_record(r.criteria_file)]
    robust = r.settings.kind.robust
    if robust is not None and robust.variation_file:
        files.append(file_record("variation (robust tuning)", robust.variation_file))
    comp = None if robust is None else robust.compensation
    if comp and Path(str(comp.get("source", ""))).is_file():
        files.append(file_record("compensation (robust tuning)", str(comp["source"])))
    changed: list[str] = []
    if rob is not None:
        more, changed = _robustness_files(rob)
        files += [*more, file_record("robustness result", rob.path)]
        comp = rob.doc.get("compensation")
        if isinstance(comp, dict) and not any(f.role == COMPENSATION_ROLE for f in more):
            files.append(FileRecord(COMPENSATION_ROLE, str(comp.get("source") or "built-in "
                                                         "default"), None,
                                    "no file: the built-in model, every value under "
                                    "Production yield"))
    if val is not None:
        files.append(file_record("validation result", val.path))
        capture = (val.single or {}).get("capture")
        if capture and Path(capture).is_file():
            files.append(file_record("capture (validation)", capture))
    if eol is not None:
        files += [file_record("EOL result", eol.path),
                  file_record("params (EOL platform setting)", eol.doc["params_file"])]
    return _dedupe(files), changed


def _repro_commands(rob: RobustnessRecord | None, r: _Run, setting: SettingRecord,
                    out: Path) -> dict[str, str]:
    """Per distinct failure (:func:`~rvmsim.report.signoff_summary.failure_groups`), for its
    first sample (the index as text): the commands that write its car as a scene (``rvmsim
    robustness … --export-sample N``) and render it in full (``rvmsim evaluate``)."""
    if rob is None or rob.inputs.get("markets"):  # no --export-sample with --markets yet
        return {}
    inputs, doc = rob.inputs, rob.doc
    params = str(inputs.get("params_file") or setting.file.path)
    crit = inputs.get("criteria_file") if inputs else (
        None if r.criteria_file is None else str(r.criteria_file))
    scale = float(inputs.get("render_scale") or 1.0)
    common = [("--criteria", crit), ("--variation", inputs.get("variation_file")),
              ("--compensation", inputs.get("compensation")),
              ("--scale", None if scale == 1.0 else f"{scale:g}")]
    opts = "".join(f" {k} {shlex.quote(str(v))}" for k, v in common if v)
    scene = next((str(f.get("path")) for f in inputs.get("files") or []
                  if isinstance(f, dict) and f.get("role") == "scene"), str(doc["scene"]))
    q = shlex.quote
    cmds = {}
    for _, group in failure_groups(rob.failing):
        n = int(group[0]["index"])
        folder = out.resolve() / f"sample_{n}"
        cmds[str(n)] = (
            f"rvmsim robustness {q(scene)} --params {q(params)} --samples "
            f"{int(doc['n'])} --seed {int(doc['seed'])}{opts} --scales 1 --out {q(str(folder))}"
            f" --export-sample {n} && rvmsim evaluate {q(str(folder / f'sample_{n}.yaml'))} "
            f"--params {q(params)}" + (f" --criteria {q(str(crit))}" if crit else "")
            + ("" if scale == 1.0 else f" --scale {scale:g}"))
    return cmds


def _check_out(out: Path) -> None:
    """``out`` must be a folder or a new one in an existing folder."""
    if out.exists() and not out.is_dir():
        raise RvmsimError(f"{out}: is a file, not a folder")
    if not out.exists() and not out.parent.is_dir():
        raise RvmsimError(f"{out.parent}: no such folder (the parent of --out)")


def _summary(res: SignoffContent, html: Path, pdf: Path | None) -> dict[str, Any]:
    """signoff.json's document."""

    checks = res.checks
    rob: dict[str, Any] | None = None
    if res.robustness is not None:
        d = res.robustness.doc
        rob = {k: d.get(k) for k in ("yield", "ci95", "n_pass", "n", "isp", "seed",
                                     "yield_by_load", "yield_before_compensation",
                                     "limiting", "compensation")}
        rob["path"] = str(res.robustness.path.resolve())
        rob["same_setting"] = res.robustness_same_setting
    return {"run": res.run_dir, "html": str(html), "pdf": None if pdf is None else str(pdf),
            "params_file": res.setting.file.path, "params_sha256": res.setting.file.sha256,
            "isp": params_to_dict(res.setting.params, res.setting.output),
            "record_output": [res.record_output.width, res.record_output.height],
            "ecs": res.ec.as_dict(), "files": [f.as_dict() for f in res.files],
            "changed_files": res.changed_files, "tool": res.provenance.as_dict(),
            "robustness": rob,
            "validation": None if res.validation is None else str(res.validation.path.resolve()),
            "eol": None if res.eol is None else str(res.eol.path.resolve()),
            "reviewer": res.reviewer, "other_setting": list(res.other_setting),
            "min_yield": res.min_yield, "passed": sheet_passes(checks),
            "checks": [{"name": ch.name, "passed": ch.passed, "detail": ch.detail}
                       for ch in checks],
            "guidelines": res.guidelines.as_dict(str(html.with_name(GUIDELINE_TABLE))),
            **_markets_summary(res)}


def _markets_summary(res: SignoffContent) -> dict[str, Any]:
    """signoff.json's ``markets`` (one row per market; a markets run only) and
    ``all_markets_pass``."""
    if res.markets is None:
        return {}
    return {"markets": markets_rows(res.markets, res.run_dir),
            "markets_trial": res.markets.get("trial"),
            "all_markets_pass": all_markets_pass(res.markets) and res.markets_same_trial}


def signoff(run_dir: str | Path, out: str | Path, *, robustness: str | Path | None = None,
            validation: str | Path | None = None, eol: str | Path | None = None,
            reviewer: str = "", pdf: bool = True, progress: bool = False,
            allow_other_setting: bool = False, min_yield: float | None = None
            ) -> SignoffResult:
    """Write the sign-off sheet of a run's best setting (see the module docstring).

    Parameters
    ----------
    run_dir : path
        A tuning run folder (``rvmsim tune``).
    out : path
        The folder to write ``signoff.html``, ``signoff.json``, ``signoff.pdf``,
        ``guidelines.bin`` (the guidelines' ECU table, when the scene has the car's running
        gear) and ``params.yaml`` (when the run has no params file of its best) into;
        created if its parent exists.
    robustness, validation, eol : path, optional
        Folders written by ``rvmsim robustness``, ``rvmsim validate`` and ``rvmsim eol``.
    reviewer : str
        The reviewer's name, printed in the signature block.
    pdf : bool
        Also print the page to PDF with headless Chromium.
    progress : bool
        Show a progress bar on stderr.
    allow_other_setting : bool
        Sign with a robustness, validation or EOL folder that judged another setting or
        another vehicle (:func:`other_setting`): the sheet then opens with a red banner
        that says so, and :attr:`SignoffResult.other_setting` lists the reasons.  Without
        it such a folder is refused.
    min_yield : float, optional
        The least production yield (0–1) that passes; default: the one the robustness
        result recorded (its ``--min-yield``, or its variation's ``min_yield``), else none
        (the yield is then shown, not judged).

    Raises
    ------
    RvmsimError
        One line naming the file: a missing or unreadable run folder, a folder without
        its result file, a corrupt result file, a folder that judged another setting or
        vehicle (unless ``allow_other_setting``), an output folder whose parent is
        missing, no Chromium for the PDF.
    """

    run_dir, out = Path(run_dir), Path(out)
    _check_out(out)
    browser = find_chromium() if pdf else None
    if pdf and browser is None:
        raise RvmsimError("chromium: not found on PATH, so no PDF can be printed (bash "
                          "tools/setup.sh installs Debian's chromium; or give --no-pdf)")
    rob = None if robustness is None else load_robustness(robustness)
    val = None if validation is None else load_validation(validation)
    eol_rec = None if eol is None else load_eol(eol)
    if not run_dir.is_dir():
        raise RvmsimError(f"{run_dir}: no such run folder")
    run = _load_run(run_dir)  # every input checked before the bar starts
    others = other_setting(run.scene.name, run.top[0].params, rob, val, eol_rec)
    if others and not allow_other_setting:
        raise RvmsimError(f"{others[0]} (rank 1 of {run_dir} is signed here; give "
                          "--allow-other-setting to sign it anyway, under a red banner)")
    bar = progress_bar(total=4 if pdf else 3, desc="signoff", unit="step", leave=False,
               disable=not progress)
    html, js = out / "signoff.html", out / SIGNOFF_JSON
    pdf_path = None
    try:
        # everything into a staging folder, moved into `out` only when all is written (a
        # failed PDF or a full disk leaves the earlier sheet as it was)
        with staged_folder(out) as stage:
            content = _content(run, out, stage, rob, val, eol_rec, reviewer, bar,
                               tuple(others), _least_yield(min_yield, rob))
            guides = content.guidelines
            if guides.reason is None:
                (stage / GUIDELINE_TABLE).write_bytes(guides.table)
            bar.set_postfix_str("writing the page")
            write_text(stage / html.name, signoff_html(content))
            bar.update()
            if browser is not None:
                bar.set_postfix_str("printing the PDF")
                f = content.setting.file
                pdf_path = out / "signoff.pdf"
                print_pdf(stage / html.name, stage / pdf_path.name, browser, (
                    f"Sign-off: {content.title}",
                    f"setting sha256 {(f.sha256 or '')[:16]} · {content.provenance.date[:10]}"))
                bar.update()
            write_text(stage / js.name, json.dumps(_summary(content, html, pdf_path),
                                                   indent=2, default=json_default) + "\n")
    finally:
        bar.close()
    f = content.setting.file
    m = content.markets
    checks = content.checks
    return SignoffResult(html, pdf_path, js, Path(f.path), f.sha256 or "", content.ec.passed,
                         None if rob is None else rob.yield_,
                         None if m is None else all_markets_pass(m) and content.markets_same_trial,
                         None if m is None else markets_verdict_text(m) if
                         content.markets_same_trial else "markets not judged for this setting",
                         content.other_setting, checks, sheet_passes(checks),
                         None if guides.reason is not None else out / GUIDELINE_TABLE,
                         guides.sha256, guides.summary_text(GUIDELINE_TABLE))


def _least_yield(given: float | None, rob: RobustnessRecord | None
                 ) -> tuple[float | None, str]:
    """The least yield that passes and where it came from: ``given`` (``--min-yield``),
    else the robustness result's record of its own, else none."""
    if given is not None:
        return given, "--min-yield"
    if rob is not None:
        recorded = rob.doc.get("min_yield")
        if isinstance(recorded, (int, float)) and 0.0 <= recorded <= 1.0:
            return float(recorded), f"the robustness run's, in {rob.path.name}"
    return None, ""


def other_setting(vehicle: str, params: IspParams, robustness: RobustnessRecord | None,
                  validation: ValidationRecord | None, eol: EolRecord | None) -> list[str]:
    """Why each given record is not of the setting ``params`` on vehicle ``vehicle``: one
    line each, naming its file, empty when every one is.

    A robustness record must have judged these 14 values (to a relative 1e-9) on this
    vehicle; an EOL record must have run this vehicle with these values as its platform
    setting (a record that does not name its platform values is checked by its vehicle
    alone); a validation must be of this vehicle.  The vehicle is the scene's ``name``.
    """
    values = params_to_dict(params)
    why: list[str] = []

    def vehicle_of(path: Path, recorded: Any) -> None:
        if isinstance(recorded, str) and recorded and recorded != vehicle:
            why.append(f"{path}: judged vehicle {recorded!r}, not {vehicle!r}")

    if robustness is not None:
        vehicle_of(robustness.path, robustness.doc.get("vehicle"))
        if not same_setting(robustness.doc["isp"], values):
            why.append(f"{robustness.path}: judged another setting (its isp differs from "
                       "the one signed)")
    if validation is not None:
        for doc in [validation.single] if validation.single is not None else validation.rows:
            if doc is not None:
                vehicle_of(validation.path, doc.get("scene"))
    if eol is not None:
        vehicle_of(eol.path, eol.doc.get("scene"))
        platform = eol.doc.get("platform_isp")
        if isinstance(platform, dict) and platform and not same_setting(platform, values):
            why.append(f"{eol.path}: judged another setting (its platform_isp differs from "
                       "the one signed)")
    return list(dict.fromkeys(why))


def _content(r: _Run, out: Path, stage: Path, rob: RobustnessRecord | None,
             val: ValidationRecord | None, eol: EolRecord | None, reviewer: str, bar: Any,
             others: tuple[str, ...] = (),
             least: tuple[float | None, str] = (None, "")) -> SignoffContent:
    """Everything the page shows: the setting, its ECs of record, the files, the commands
    (a params file of its own written into ``stage``, the staging folder of ``out``)."""

    best = r.top[0]
    setting = SettingRecord(best.params, r.output, _params_record(r, out, stage))
    record = _record_output(r.criteria, r.scene, r.output)
    bar.set_postfix_str(f"ECs at {record.width}x{record.height}")
    ec, color, annotated, each = _record_ecs(r.images, best.params, record, r.criteria)
    guides = guideline_figures(r.scene, best.params, r.output, r.images,
                               shown=(record, color))
    bar.update()
    bar.set_postfix_str("hashing the inputs")
    files, changed = _files(r, setting, rob, val, eol)
    same = rob is None or same_setting(rob.doc["isp"], params_to_dict(best.params))
    markets = load_markets(r.run_dir)
    bar.update()
    return SignoffContent(
        title=r.scene.name, run_dir=str(r.run_dir.resolve()), setting=setting, files=files,
        provenance=provenance(), record_output=record, tuning_output=r.output, ec=ec,
        display=color, annotated=annotated, ec_pictures=each, robustness=rob,
        robustness_same_setting=same, changed_files=changed, validation=val, eol=eol,
        reviewer=reviewer, repro=_repro_commands(rob, r, setting, out), markets=markets,
        markets_same_trial=markets is None or markets.get("trial") == best.idx,
        other_setting=others, min_yield=least[0], min_yield_source=least[1],
        guidelines=guides)
