"""CLI: `rvmsim render` writes the images people and later stages use."""

from __future__ import annotations

import json
import shlex
import subprocess
import sys

import click
import yaml

import imageio.v3 as iio
import pytest
import numpy as np

from rvmsim import labels as L

from .cli_runner import child_env, run_in_process, tune_status
from .conftest import SCENES
from rvmsim.testing.scenes import write_small_scene
from rvmsim.testing.stations import TUNED


def test_render_writes_color_labels_preview_and_metadata(tmp_path):
    out = tmp_path / "a"
    res = run_in_process(["render", str(SCENES / "vehicle_a.yaml"), "--out",
                          str(out), "--scale", "0.25", "--no-progress"])
    assert res.code == 0, res.stderr
    color = iio.imread(out / "fisheye_color.png")
    labels = iio.imread(out / "fisheye_labels.png")
    preview = iio.imread(out / "fisheye_labels_preview.png")
    assert color.shape == (240, 320, 3) and color.dtype == np.uint8
    assert labels.shape == (240, 320) and labels.dtype == np.uint8
    assert np.array_equal(preview, L.colorize(labels))
    meta = json.loads((out / "render.json").read_text())
    assert meta["image_size"] == [320, 240]
    present = {int(k) for k in meta["labels_present"]}
    assert present == set(np.unique(labels).tolist())
    assert {L.BUMPER, L.BOARD, L.object_patch("F")} <= present
    assert "rendered Vehicle A" in res.stdout


def test_render_unwritable_output_is_one_line(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = run_in_process(["render", str(SCENES / "vehicle_a.yaml"), "--out",
                          str(blocker / "sub"), "--scale", "0.1", "--no-progress"])
    assert res.code == 2
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr


def test_process_writes_rvm_images_and_roi(tmp_path):
    params = tmp_path / "p.yaml"
    params.write_text("rad: 612\nzoom: 0.6\nadv_v_shift: 0.2\noutput: {size: [320, 180]}\n")
    out = tmp_path / "proc"
    res = run_in_process(["process", str(SCENES / "vehicle_a.yaml"), "--params",
                          str(params), "--out", str(out), "--scale", "0.25", "--no-progress"])
    assert res.code == 0, res.stderr
    labels = iio.imread(out / "rvm_labels.png")
    color = iio.imread(out / "rvm_color.png")
    roi = iio.imread(out / "fisheye_roi.png")
    assert labels.shape == (180, 320) and color.shape == (180, 320, 3)
    assert np.array_equal(iio.imread(out / "rvm_labels_preview.png"), L.colorize(labels))
    assert {L.BOARD, L.BUMPER, L.guide_cross(2)} <= set(np.unique(labels).tolist())
    green = (roi[..., 1] > 200) & (roi[..., 0] < 80) & (roi[..., 2] < 80)
    assert green.sum() > 100 and roi.shape == (240, 320, 3)
    assert json.loads((out / "isp.json").read_text())["zoom"] == 0.6


def test_process_bad_params_is_one_line(tmp_path):
    params = tmp_path / "p.yaml"
    params.write_text("zoom: 20\n")
    res = run_in_process(["process", str(SCENES / "vehicle_a.yaml"), "--params", str(params),
                          "--out", str(tmp_path / "o"), "--scale", "0.1", "--no-progress"])
    assert res.code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "zoom: 20 is outside" in lines[0] and str(params) in lines[0]
    assert not (tmp_path / "o").exists()


def test_evaluate_prints_table_writes_json_and_annotated_image(tmp_path):
    params = tmp_path / "p.yaml"
    params.write_text("rad: 612\nzoom: 0.5\nadv_v_shift: 0.2\noutput: {size: [320, 180]}\n")
    crit = tmp_path / "c.yaml"
    crit.write_text("name: OEM test\ncriteria:\n  4-1: {enabled: false}\n")
    out = tmp_path / "ev"
    res = run_in_process(["evaluate", str(SCENES / "vehicle_a.yaml"), "--params", str(params),
                          "--criteria", str(crit), "--out", str(out), "--scale", "0.25",
                          "--no-progress"])
    assert res.code == 1, res.stderr  # 1-3, 2-1, 2-2 and 3-2 fail at this setting
    failing = [e["id"] for e in json.loads((out / "ec.json").read_text())["ecs"]
               if e["enabled"] and not e["passed"]]
    assert failing and res.stderr == f"not every EC passes: {', '.join(failing)}\n"
    for ec in ("1-1", "2-3", "4-1"):
        assert f"\n{ec} " in res.stdout
    assert "OEM test" in res.stdout and "EC score" in res.stdout
    # a file searched at 320 × 180 is judged at the RVM image of record, and says so
    assert "judged at the RVM image of record, 1280x720 px" in res.stdout
    doc = json.loads((out / "ec.json").read_text())
    assert doc["judged_at"] == [1280, 720] and doc["isp"]["output"]["judged_at"] == [1280, 720]
    assert iio.imread(out / "rvm_labels.png").shape == (720, 1280)
    assert [e["id"] for e in doc["ecs"]][:2] == ["1-1", "1-2"]
    enabled = [e for e in doc["ecs"] if e["enabled"]]
    assert len(enabled) == 10
    assert doc["ec_score"] == pytest.approx(float(np.prod([e["score"] for e in enabled])))
    ann = iio.imread(out / "ec_annotated.png")
    assert ann.shape[0] >= 180 and ann.shape[1] > 320  # image + results panel
    labels = iio.imread(out / "rvm_labels.png")
    from rvmsim.criteria import evaluate, load_criteria

    assert evaluate(labels, load_criteria(crit)).score == pytest.approx(doc["ec_score"])


def test_evaluate_exits_0_when_every_ec_passes(tmp_path):
    """evaluate judges: 0 when every EC passes at the RVM image of record (vehicle A's
    tuned setting), 1 when one fails (the test above), 2 on an error (the test below)."""
    res = run_in_process(["evaluate", str(SCENES / "vehicle_a.yaml"), "--params", str(TUNED),
                          "--out", str(tmp_path / "ev"), "--scale", "0.25", "--no-progress"])
    assert res.code == 0, res.stderr
    assert json.loads((tmp_path / "ev" / "ec.json").read_text())["passed"]
    assert res.stderr == ""


def test_evaluate_says_when_it_judges_at_another_size_than_the_params_file_was(tmp_path):
    """A params file judged at 640 × 360 (its output.judged_at) evaluated on a scene whose
    RVM image of record is 1280 × 720: one line says so; the same size says nothing."""
    text = TUNED.read_text()
    for judged, note in (([640, 360], True), ([1280, 720], False)):
        params = tmp_path / f"p{judged[0]}.yaml"
        params.write_text(text.replace("output:", f"output:\n  judged_at: {judged}", 1)
                          if "output:" in text else text + f"output: {{judged_at: {judged}}}\n")
        res = run_in_process(["evaluate", str(SCENES / "vehicle_a.yaml"), "--params",
                              str(params), "--out", str(tmp_path / "ev"), "--scale", "0.25",
                              "--no-progress"])
        assert res.code in (0, 1), res.stderr
        lines = [ln for ln in res.stderr.splitlines() if "judged_at" in ln]
        if note:
            assert lines == [f"rvmsim: note: {params}: output.judged_at is 640x360; judged "
                             f"here at {SCENES / 'vehicle_a.yaml'}'s RVM image of record, "
                             "1280x720 px"]
        else:
            assert lines == []


def test_evaluate_bad_criteria_is_one_line(tmp_path):
    crit = tmp_path / "c.yaml"
    crit.write_text("criteria:\n  9-9: {}\n")
    res = run_in_process(["evaluate", str(SCENES / "vehicle_a.yaml"),
                          "--criteria", str(crit), "--out", str(tmp_path / "o"), "--scale", "0.1"])
    assert res.code == 2 and "9-9" in res.stderr and "Traceback" not in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


def _rvmsim(*args, env=None):
    return run_in_process(args, env=env)


def _assert_runnable_as_printed(steps: list[str], scene) -> None:
    """Each printed next command gives every option its command requires, and no
    placeholder but ``K`` (the rank to choose): click parses it as printed."""
    from rvmsim.cli import cli
    ctx = click.Context(cli)
    for line in steps:
        command = shlex.split(line.split("   ")[0].strip())
        assert command[0] == "rvmsim", line
        sub = cli.get_command(ctx, command[1])
        assert sub is not None, line
        ctx = sub.make_context(command[1], command[2:], resilient_parsing=True)
        missing = [p.name for p in sub.params if p.required and ctx.params.get(p.name) is None]
        assert not missing, (line, missing)
        assert not {"SCENE", "DIR"} & set(command), line
        if command[1] == "robustness":
            assert command[2] == str(scene), line


def test_tune_status_select_and_batch(tmp_path):
    """Vehicles A and B on a quarter of their sensors (the RVM images keep their sizes)."""
    env = {"RVMSIM_CACHE": str(tmp_path / "cache")}
    scene_a, scene_b = (write_small_scene(tmp_path, letter) for letter in "ab")
    cfg = tmp_path / "t.yaml"
    cfg.write_text("tuned: [zoom, adv_v_shift, adv_v_scale]\noutput: {size: [320, 180]}\n"
                   "top_m: 3\nbatch: 50\n")
    run = tmp_path / "runs" / "a"
    res = _rvmsim("tune", str(scene_a), "--out", str(run), "--config",
                  str(cfg), "--strategy", "random", "--budget", "120", "--workers", "2",
                  "--no-progress", env=env)
    assert res.code == tune_status(run), res.stderr
    assert "120 evaluated" in res.stdout and "EC score" in res.stdout
    # it ends with where the results are and the commands that come next
    tail = res.stdout.splitlines()
    assert f"run folder: {run}" in tail and "next:" in tail
    best = next(ln for ln in tail if ln.startswith("best setting: "))
    assert best.startswith(f"best setting: {run / 'top' / 'rank_1.yaml'} ")
    for command in ("report", "console", "select", "robustness", "signoff"):
        assert any(ln.startswith(f"  rvmsim {command} ") for ln in tail), command
    _assert_runnable_as_printed(tail[tail.index("next:") + 1:], scene_a)
    for name in ("run.sqlite", "run.json", "best/rvm_color.png", "best/ec_annotated.png",
                 "best/ec.json", "top/rank_1.yaml", "top/rank_3.yaml"):
        assert (run / name).is_file(), name
    # searched at 320 × 180, judged (and shown) at the RVM image of record
    assert iio.imread(run / "best" / "rvm_display.png").shape == (720, 1280, 3)
    assert iio.imread(run / "best" / "rvm_color.png").shape == (720, 1280, 3)
    assert json.loads((run / "best" / "ec.json").read_text())["judged_at"] == [1280, 720]
    assert json.loads((run / "run.json").read_text())["judged_at"] == [1280, 720]
    st = _rvmsim("status", str(run), env=env)
    assert st.code == 0 and "120 / 120 evaluations" in st.stdout and "#3" in st.stdout
    sel = _rvmsim("select", str(run), "--rank", "2", "--out", str(tmp_path / "p2.yaml"), env=env)
    assert sel.code == 0
    from rvmsim.isp import load_params

    params, out = load_params(tmp_path / "p2.yaml")
    assert out.width == 320 and params.zoom > 0
    exported = yaml.safe_load((tmp_path / "p2.yaml").read_text())
    assert exported["output"]["judged_at"] == [1280, 720]
    assert "judged at the RVM image of record, 1280x720" in (tmp_path / "p2.yaml").read_text()
    # The exported file reproduces the stored score through the public pipeline.
    from rvmsim.runs import RunStore

    store = RunStore(run / "run.sqlite")
    second = store.top(2)[1]
    store.close()
    assert params == second.params
    # A second tune into the same folder refuses to overwrite it.
    again = _rvmsim("tune", str(scene_a), "--out", str(run), "--no-progress",
                    env=env)
    assert again.code == 2 and "--resume" in again.stderr
    # Batch: one good scene, one broken one; the broken one is reported and skipped.
    broken = tmp_path / "broken.yaml"
    broken.write_text("name: x\ncamera: {\n")
    b = _rvmsim("batch", str(scene_b), str(broken), "--out",
                str(tmp_path / "batch"), "--config", str(cfg), "--strategy", "random",
                "--budget", "60", "--workers", "1", "--no-progress", env=env)
    assert b.code == 1
    assert "broken.yaml" in b.stderr and "skipped" in b.stderr
    summary = json.loads((tmp_path / "batch" / "summary.json").read_text())
    assert summary[0]["vehicle"].startswith("Vehicle B") and summary[0]["evaluations"] == 60
    assert "error" in summary[1]
    assert "Vehicle B" in (tmp_path / "batch" / "summary.txt").read_text()
    # With progress bars, off a terminal (a log): plain lines only after 10 s, so a short
    # batch writes none (a whole tune of vehicle A writes two lines: 204 bytes, not 58 KB)
    b = _rvmsim("batch", str(scene_b), str(broken), "--out",
                str(tmp_path / "batch2"), "--config", str(cfg), "--strategy", "random",
                "--budget", "60", "--workers", "1", env=env)
    assert b.code == 1 and "skipped" in b.stderr
    assert "\r" not in b.stderr and "eval/s" not in b.stderr and "%|" not in b.stderr


def test_tune_errors_are_one_line(tmp_path):
    bad = tmp_path / "t.yaml"
    bad.write_text("tuned: [zooom]\n")
    res = _rvmsim("tune", str(SCENES / "vehicle_a.yaml"), "--config", str(bad), "--out",
                  str(tmp_path / "r"))
    assert res.code == 2 and "zooom" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    res = _rvmsim("tune", "--resume", str(tmp_path / "nothing"))
    assert res.code == 2 and "no run to resume" in res.stderr
    res = _rvmsim("status", str(tmp_path / "nothing"))
    assert res.code == 2
    assert res.stderr == f"rvmsim: error: {tmp_path / 'nothing'}: no such run folder\n"
    res = _rvmsim("status", str(tmp_path))  # a folder, but not a run's
    assert res.code == 2 and res.stderr == \
        f"rvmsim: error: {tmp_path}: not a run folder (no run.sqlite in it)\n"


def test_strategy_choices_come_from_the_registry():
    from click.testing import CliRunner

    from rvmsim.cli import cli
    from rvmsim.search import STRATEGIES

    runner = CliRunner()
    for command in ("tune", "batch"):
        res = runner.invoke(cli, [command, "--help"])
        assert res.exit_code == 0
        words = " ".join(res.output.split())
        for name, cls in STRATEGIES.items():
            assert f"{name}: {cls.summary}" in words, (command, name)
    res = runner.invoke(cli, ["tune", str(SCENES / "vehicle_a.yaml"), "--strategy", "annealing"])
    assert res.exit_code == 2
    assert "'grid-random', 'cmaes', 'cmaes-solved', 'random'" in " ".join(res.output.split())


COMMANDS = ("render", "process", "evaluate", "tune", "batch", "status", "select", "report",
            "judge", "validate", "sweep")


def _main(*args):
    """``rvmsim ARGS`` through the console-script entry point, in this process: (exit status,
    stdout, stderr)."""
    res = run_in_process(args)
    return res.code, res.stdout, res.stderr


@pytest.mark.parametrize("command", COMMANDS)
def test_help_of_every_command_still_works(command):
    code, out, err = _main(command, "--help")
    assert code == 0 and err == ""
    assert f"{command} [OPTIONS]" in out and "--help" in out and "Options:" in out


def test_top_level_help_and_version_still_work():
    from importlib.metadata import version

    code, out, err = _main("--help")
    assert code == 0 and err == "" and all(c in out for c in COMMANDS)
    code, out, err = _main("-h")
    assert code == 0 and "Commands:" in out
    code, out, err = _main("--version")
    assert code == 0 and version("rvmsim") in out


@pytest.mark.parametrize("args, line", [
    (("tune", "--budget", "x"), "rvmsim tune: --budget: 'x' is not a valid integer"),
    (("render", "s.yaml", "--out"), "rvmsim render: option '--out' requires an argument"),
    (("status",), "rvmsim status: RUN: required argument not given"),
    (("select", "r", "--rnak", "2"),
     "rvmsim select: --rnak: no such option (did you mean --rank?)"),
    (("validate", "s.yaml"), "rvmsim validate: --capture: required option not given"),
    (("report", "a", "b"), "rvmsim report: got unexpected extra argument (b)"),
    (("tune", "s.yaml", "--force=yes"), "rvmsim tune: option '--force' does not take a value"),
    (("tune", "--resume"), "rvmsim tune: option '--resume' requires an argument"),
    (("tune", "s.yaml", "--max-time", "nan"),
     "rvmsim tune: --max-time: 'nan' is not a finite number"),
])
def test_usage_errors_are_one_line_naming_the_option(args, line):
    code, out, err = _main(*args)
    assert code == 2 and out == "" and err == line + "\n"


def test_no_command_is_one_line_listing_the_commands():
    code, out, err = _main()
    assert code == 2 and len(err.splitlines()) == 1
    assert err.startswith("rvmsim: missing command") and all(c in err for c in COMMANDS)


def test_sweep_accepts_allow_large():
    code, out, err = _main("sweep", "--help")
    assert code == 0 and "--allow-large" in out
    assert "design points" in " ".join(out.split())


def test_good_invocations_use_existing_outputs(tmp_path):
    """An existing output folder and an existing params file are still fine: the option types
    only refuse a file where a folder goes (and the reverse)."""
    out = tmp_path / "already"
    out.mkdir()
    res = run_in_process(["render", str(SCENES / "vehicle_a.yaml"), "--out", str(out),
                          "--scale", "0.1", "--no-progress"])
    assert res.code == 0, res.stderr
    assert (out / "fisheye_labels.png").is_file() and "rendered Vehicle A" in res.stdout
    from click.testing import CliRunner

    from rvmsim.cli import cli

    params = tmp_path / "p.yaml"
    params.write_text("old\n")
    res2 = CliRunner().invoke(cli, ["select", str(tmp_path / "nothing"), "--out", str(params)])
    assert res2.exit_code == 2 and "--out" not in res2.output  # the run is at fault, not --out


def test_every_command_reports_its_errors_through_the_one_hook():
    """Every command is a :class:`rvmsim.cli.errors.Command` (so none needs an ``except``
    of its own), and the group holds exactly the commands the modules define."""
    import importlib

    import click

    from rvmsim.cli import COMMAND_MODULES, cli
    from rvmsim.cli.errors import Command

    ctx = click.Context(cli)
    assert cli.list_commands(ctx) == sorted(COMMAND_MODULES)
    loaded = {name: cli.get_command(ctx, name) for name in COMMAND_MODULES}
    assert all(isinstance(c, Command) and c.name == name for name, c in loaded.items())
    defined = {c.name for module in set(COMMAND_MODULES.values())
               for c in vars(importlib.import_module(module)).values()
               if isinstance(c, click.Command)}
    assert defined == set(COMMAND_MODULES)
    assert cli.get_command(ctx, "tunes") is None


def test_a_command_imports_its_own_module_alone():
    """``rvmsim tune`` imports the tuning commands' module, not the console's, the
    sign-off's or the report's (the time before a run's first candidate), and the tuning
    package does not import scipy.stats (cmaes does, for the CMA-ES strategies only)."""
    script = ("import sys\n"
              "from rvmsim.cli.group import main\n"
              "try:\n"
              "    main(['tune', '--help'])\n"
              "except SystemExit as stop:\n"
              "    assert stop.code == 0, stop.code\n"
              "print('modules:', *sorted(m for m in sys.modules\n"
              "                          if m.startswith(('rvmsim', 'scipy.stats', 'cmaes'))))\n")
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env=child_env(), timeout=120)
    assert res.returncode == 0, res.stderr
    modules = set(res.stdout.splitlines()[-1].split()[1:])
    assert "rvmsim.cli.tune" in modules and "rvmsim.tune" in modules
    assert not {"rvmsim.cli.console", "rvmsim.cli.signoff", "rvmsim.cli.report",
                "rvmsim.console", "rvmsim.report"} & modules
    assert not {"scipy.stats", "cmaes"} & modules


def _failing_command(raised: BaseException):
    """A command of the CLI's kind whose body raises ``raised`` (as a library call would),
    with ``--out`` defaulting to ``out/<SCENE name>/x``."""
    from pathlib import Path

    import click

    from rvmsim.cli.errors import Command
    from rvmsim.cli.params import OutputFolder, default_folder

    @click.command(cls=Command, error_path=("out",))
    @click.argument("scene", type=click.Path(path_type=Path))
    @click.option("--out", type=OutputFolder(), default=None,
                  callback=default_folder("scene", lambda s: Path("out") / s.stem / "x"))
    def command(scene: Path, out: Path) -> None:
        click.echo(f"out={out}")
        raise raised

    return command


@pytest.mark.parametrize("raised, line", [
    (RuntimeError("x"), None),  # not ours: not mapped
    (FileNotFoundError(2, "No such file or directory", "in.png"),
     "rvmsim: error: in.png: No such file or directory"),
    (OSError(28, "No space left on device"), "rvmsim: error: {out}: the disk is full (No space left on device)"),
])
def test_the_hook_maps_os_errors_naming_their_file_else_the_output_folder(
        tmp_path, monkeypatch, raised, line):
    from click.testing import CliRunner

    from rvmsim.errors import SceneError

    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    res = runner.invoke(_failing_command(raised), ["s.yaml"])
    if line is None:
        assert res.exit_code == 1 and res.exception is raised
        return
    assert res.exit_code == 2 and res.stdout == "out=out/s/x\n"
    assert res.stderr == line.format(out="out/s/x") + "\n"
    res = runner.invoke(_failing_command(raised), ["--out", "o", "s.yaml"])  # --out first
    assert res.exit_code == 2 and res.stderr == line.format(out="o") + "\n"
    res = runner.invoke(_failing_command(SceneError("s.yaml", "camera.fx", "must be > 0", 3)),
                        ["s.yaml"])
    assert res.exit_code == 2 and res.stderr == "rvmsim: error: s.yaml:3: camera.fx: must be > 0\n"


def test_main_takes_its_arguments(capsys, tmp_path):
    """``main(args)`` runs those arguments in this process (``sys.argv`` is not read) and
    exits with the command's status."""
    from rvmsim.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["status", str(tmp_path / "nothing")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.startswith("rvmsim: error: ")
    assert "no such run folder" in err and len(err.splitlines()) == 1
    with pytest.raises(SystemExit) as stop:
        main(("render", "--out"))
    assert stop.value.code == 2
    assert capsys.readouterr().err == "rvmsim render: option '--out' requires an argument\n"
    with pytest.raises(SystemExit) as stop:
        main(["--help"])
    assert stop.value.code == 0 and "Usage: rvmsim [OPTIONS] COMMAND" in capsys.readouterr().out
