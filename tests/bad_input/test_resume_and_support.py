"""Issue #30's run and scene classes: ``tune --resume RUN`` given a scene or a run option
that is not the run's own, a run.json that disagrees with run.sqlite, a scene whose
criteria it cannot support (tune, evaluate, robustness), a shared run whose scenes no
setting passes together, and ``--robust``'s help.  Refusals are one stderr line naming the
file and key, exit status 2, no traceback, the run folder byte-identical (and untouched:
same modification times)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from rvmsim.tune.robust import ROBUST_AGGREGATE

from .conftest import SMALL_SCENE, small_scene
from ..cli_runner import REPO, run_in_process, tune_status
from .harness import Case, check_case

S = SMALL_SCENE
RESUME = ("--resume", "run", "--workers", "1", "--no-progress")
NEW = ("--out", "new", "--workers", "1", "--no-progress")
REAL = str(REPO / "scenes" / "real" / "baic_eu5_rear.yaml")


def _scene(name: str, edit: dict):
    """A setup writing the small scene with ``edit`` as ``name``."""
    def setup(folder: Path) -> None:
        sub = folder / "variant"
        sub.mkdir(exist_ok=True)
        small_scene(sub, edit)
        shutil.move(sub / S, folder / name)
        sub.rmdir()
    return setup


def _copy(name: str):
    def setup(folder: Path) -> None:
        shutil.copy(folder / S, folder / name)
    return setup


def _write(name: str, text: str):
    def setup(folder: Path) -> None:
        (folder / name).write_text(text)
    return setup


def _edit_run_json(**changes):
    """A setup changing keys of run/run.json (as a user editing it would)."""
    def setup(folder: Path) -> None:
        path = folder / "run" / "run.json"
        doc = json.loads(path.read_text())
        doc.update(changes)
        path.write_text(json.dumps(doc, indent=2))
    return setup


OTHER = _scene("b.yaml", {"vehicle.bumper.top": 0.8})
NO_BOARD = {"test_site.board.enabled": False}

RESUME_CASES = [
    # 1: a scene or option given with --resume that the run was not made with
    Case("resume-other-scene", ("tune", "b.yaml", *RESUME),
         ("b.yaml", "scene.yaml", "another scene", "--resume"), setup=OTHER, keep=("run",)),
    Case("resume-missing-scene", ("tune", "gone.yaml", *RESUME), ("gone.yaml",),
         keep=("run",)),
    Case("resume-two-scenes-for-one", ("tune", S, "b.yaml", *RESUME),
         ("2 scenes", "run.sqlite", "--resume"), setup=OTHER, keep=("run",)),
    Case("resume-budget", ("tune", *RESUME, "--budget", "80"),
         ("--budget 80", "run.sqlite", "--budget 40"), keep=("run",)),
    Case("resume-strategy", ("tune", *RESUME, "--strategy", "cmaes"),
         ("--strategy cmaes", "run.sqlite", "random"), keep=("run",)),
    Case("resume-seed", ("tune", *RESUME, "--seed", "7"),
         ("--seed 7", "run.sqlite", "--seed 0"), keep=("run",)),
    Case("resume-criteria", ("tune", *RESUME, "--criteria", "unr158"),
         ("--criteria unr158", "run.sqlite", "paper's criteria"), keep=("run",)),
    Case("resume-config", ("tune", *RESUME, "--config", "tune.yaml"),
         ("--config tune.yaml", "run.sqlite", "batch"),
         setup=_write("tune.yaml", "batch: 7\n"), keep=("run",)),
    Case("resume-aggregate", ("tune", *RESUME, "--aggregate", "min"),
         ("--aggregate", "run.sqlite"), keep=("run",)),
    Case("resume-samples", ("tune", *RESUME, "--robust", "--samples", "4"),
         ("--robust", "run.sqlite", "without --robust"), keep=("run",)),
    Case("resume-force", ("tune", *RESUME, "--force"), ("--force", "--resume"), keep=("run",)),
    Case("resume-out-elsewhere", ("tune", *RESUME, "--out", "elsewhere"),
         ("--out elsewhere", "--resume"), keep=("run",)),
    Case("resume-only-supported", ("tune", *RESUME, "--only-supported"),
         ("--only-supported", "run.sqlite"), keep=("run",)),
    # 5: run.json edited (settings live in run.sqlite): refused, naming run.json and the key
    Case("resume-run-json-budget", ("tune", *RESUME),
         ("run.json", "budget", "run.sqlite"), setup=_edit_run_json(budget=80), keep=("run",)),
    Case("resume-run-json-strategy", ("tune", *RESUME),
         ("run.json", "strategy", "run.sqlite"), setup=_edit_run_json(strategy="cmaes"),
         keep=("run",)),
    Case("resume-run-json-config-key", ("tune", *RESUME),
         ("run.json", "config.batch", "run.sqlite"),
         setup=lambda d: _edit_run_json(config={
             **json.loads((d / "run" / "run.json").read_text())["config"], "batch": 3})(d),
         keep=("run",)),
    Case("resume-run-json-junk", ("tune", *RESUME), ("run.json", "JSON"),
         setup=_write("run/run.json", "{\"budget\": "), keep=("run",)),
]

SUPPORT_CASES = [
    # 3: a scene its criteria cannot measure, refused before any work
    Case("tune-real-scene-nothing-to-measure", ("tune", REAL, *NEW),
         ("baic_eu5_rear.yaml", "1-1", "3-1", "4-1", "test_site.board.enabled",
          "test_site.guidelines.enabled", "test_site.objects.F.enabled", "--only-supported")),
    Case("tune-board-disabled", ("tune", "nb.yaml", *NEW),
         ("nb.yaml", "4-1", "test_site.board.enabled: false"), setup=_scene("nb.yaml", NO_BOARD)),
    Case("tune-object-f-disabled", ("tune", "nf.yaml", *NEW),
         ("nf.yaml", "EC 1-1 (", "test_site.objects.F.enabled: false"),  # 1-2: G counts
         setup=_scene("nf.yaml", {"test_site.objects.F.enabled": False})),
    Case("tune-one-cross-line", ("tune", "cz.yaml", *NEW),
         ("cz.yaml", "3-1", "3-2", "test_site.guidelines.cross_z"),
         setup=_scene("cz.yaml", {"test_site.guidelines.cross_z": [0.5]})),
    Case("tune-shared-second-scene-unsupported", ("tune", S, "nb.yaml", "--shared", *NEW),
         ("nb.yaml", "4-1", "test_site.board.enabled"), setup=_scene("nb.yaml", NO_BOARD)),
    Case("tune-robust-unsupported", ("tune", "nb.yaml", "--robust", "--samples", "2", *NEW),
         ("nb.yaml", "4-1"), setup=_scene("nb.yaml", NO_BOARD)),
    Case("evaluate-board-disabled", ("evaluate", "nb.yaml", "--out", "new", "--no-progress"),
         ("nb.yaml", "4-1", "test_site.board.enabled"), setup=_scene("nb.yaml", NO_BOARD)),
    Case("evaluate-real-scene", ("evaluate", REAL, "--out", "new", "--no-progress"),
         ("baic_eu5_rear.yaml", "4-1", "--only-supported")),
    Case("robustness-board-disabled", ("robustness", "nb.yaml", "--params",
                                       "run/top/rank_1.yaml", "--samples", "2", "--out", "new",
                                       "--workers", "1", "--no-progress"),
         ("nb.yaml", "4-1", "test_site.board.enabled"), setup=_scene("nb.yaml", NO_BOARD)),
]


def _mtimes(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): p.stat().st_mtime_ns
            for p in sorted(folder.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("case", RESUME_CASES, ids=[c.id for c in RESUME_CASES])
def test_a_resume_given_what_the_run_is_not_is_refused_and_changes_nothing(case, case_dir):
    if case.setup is not None:  # before the times are taken: a run.json edit is the case's
        case.setup(case_dir)
    before = _mtimes(case_dir / "run")
    check_case(Case(case.id, case.args, case.names, keep=case.keep), case_dir)
    assert _mtimes(case_dir / "run") == before  # not rewritten, not even with the same bytes


@pytest.mark.parametrize("case", SUPPORT_CASES, ids=[c.id for c in SUPPORT_CASES])
def test_a_scene_that_cannot_support_its_ecs_is_refused_before_any_work(case, case_dir):
    check_case(case, case_dir)
    assert not (case_dir / "new").exists()  # nothing rendered, tuned or written


def test_a_resume_given_the_runs_own_scene_by_path_or_content_continues(case_dir):
    """The run's own scene (its file, or a copy with the same content) and its own options
    are accepted: the run continues with its settings."""
    _copy("copy.yaml")(case_dir)
    for scene in (S, "copy.yaml"):
        out = run_in_process(["tune", scene, *RESUME, "--budget", "40", "--strategy", "random",
                              "--seed", "0", "--out", "run"], cwd=case_dir)
        assert out.code == tune_status(case_dir / "run"), out.stderr
        assert "0 evaluated, 40 replayed" in out.stdout


def test_status_says_when_run_json_disagrees_with_the_store(case_dir):
    out = run_in_process(["status", "run"], cwd=case_dir)
    assert out.code == 0 and "run.json" not in out.stdout, out.stdout
    _edit_run_json(budget=80)(case_dir)
    out = run_in_process(["status", "run"], cwd=case_dir)
    assert out.code == 0, out.stderr
    said = [ln for ln in out.stdout.splitlines() if "run.json" in ln]
    assert len(said) == 1 and "budget is 80" in said[0] and "run.sqlite holds 40" in said[0]


def test_only_supported_tunes_the_rest_and_resumes_with_them(case_dir):
    _scene("nb.yaml", NO_BOARD)(case_dir)
    args = ["tune", "nb.yaml", "--strategy", "random", "--budget", "10", "--out", "nb",
            "--workers", "1", "--no-progress", "--only-supported"]
    out = run_in_process(args, cwd=case_dir)
    assert out.code == tune_status(case_dir / "nb"), out.stderr
    assert json.loads((case_dir / "nb" / "run.json").read_text())["only_supported"] == \
        {"left_out": ["4-1"]}
    ecs = {e["id"]: e for e in json.loads((case_dir / "nb" / "best" / "ec.json").read_text())
           ["ecs"]}
    assert not ecs["4-1"]["enabled"] and ecs["4-1"]["value"] is None
    assert all(e["enabled"] for k, e in ecs.items() if k != "4-1")
    again = run_in_process(["tune", "--resume", "nb", "--workers", "1", "--no-progress"],
                           cwd=case_dir)
    assert again.code == out.code and "10 replayed" in again.stdout, again.stderr
    assert json.loads((case_dir / "nb" / "best" / "ec.json").read_text())["ecs"] == \
        list(ecs.values())


def test_a_shared_run_no_setting_passes_exits_1_naming_the_ecs_and_scenes(case_dir):
    """Two scenes, a search too short for any setting to pass both: exit 1, and one line per
    failing EC with its value on each scene where it fails, against its range."""
    OTHER(case_dir)
    out = run_in_process(["tune", S, "b.yaml", "--shared", "--strategy", "random", "--budget",
                          "10", "--out", "shared", "--workers", "1", "--no-progress"],
                         cwd=case_dir)
    doc = json.loads((case_dir / "shared" / "best" / "members.json").read_text())
    assert not all(m["passed"] for m in doc["members"])
    assert out.code == 1, out.stderr
    assert "no setting found passes every scene" in out.stdout
    for m in doc["members"]:
        for ec in m["ecs"]:
            if ec["enabled"] and not ec["passed"]:
                line = next(ln for ln in out.stdout.splitlines()
                            if ln.strip().startswith(f"EC {ec['id']} "))
                shown = "—" if ec["value"] is None else f"{ec['value']:.4g}"
                assert f"{shown}{' ' + ec['unit'] if ec['unit'] else ''} on {m['vehicle']}" \
                    in line, line
                assert "needs" in line


def test_robust_help_gives_the_default_aggregate():
    out = run_in_process(["tune", "--help"])
    text = " ".join(out.stdout.split())
    assert out.code == 0 and "worst sample's" not in text
    robust = text[text.index("--robust "):text.index("--samples ")]
    assert f"[default: {ROBUST_AGGREGATE};" in robust and "--aggregate min" in robust
