"""The option types of the CLI: each refuses what the pipeline cannot use, by the option's
name, and keeps everything it can."""

from __future__ import annotations

import math

import click
import pytest

from rvmsim.cli.errors import usage_error_line
from rvmsim.cli.params import (SEED, FiniteFloat, Integer, OutputFile, OutputFolder,
                               SchedulerAddress)


def _convert(ptype: click.ParamType, value: str):
    return ptype.convert(value, None, None)


@pytest.mark.parametrize("value", ["nan", "NaN", "inf", "-inf", "1e400"])
def test_finite_float_refuses_nan_and_inf(value):
    with pytest.raises(click.BadParameter, match="not a finite number"):
        _convert(FiniteFloat(), value)
    with pytest.raises(click.BadParameter):
        _convert(FiniteFloat(0, 10), value)


def test_finite_float_keeps_its_range_and_good_values():
    assert _convert(FiniteFloat(0.05, 4.0), "0.25") == 0.25
    assert _convert(FiniteFloat(0), "1e300") == 1e300
    with pytest.raises(click.BadParameter, match="not in the range"):
        _convert(FiniteFloat(0.05, 4.0), "5")
    with pytest.raises(click.BadParameter, match="'x' is not a valid number"):
        _convert(FiniteFloat(0), "x")
    assert math.isfinite(_convert(FiniteFloat(), "-3"))


def test_integer_and_seed():
    assert _convert(Integer(1, 64), "8") == 8
    with pytest.raises(click.BadParameter, match=r"'x' is not a valid integer\.$"):
        _convert(Integer(1), "x")
    assert _convert(SEED, str(2**32 - 1)) == 2**32 - 1
    for bad in ("-1", str(2**32)):
        with pytest.raises(click.BadParameter, match="not in the range"):
            _convert(SEED, bad)


def test_output_folder(tmp_path):
    blocker = tmp_path / "f"
    blocker.write_text("x")
    assert _convert(OutputFolder(), str(tmp_path)) == tmp_path
    assert _convert(OutputFolder(), str(tmp_path / "new" / "deeper")) == tmp_path / "new" / "deeper"
    with pytest.raises(click.BadParameter, match="f is a file, not a folder"):
        _convert(OutputFolder(), str(blocker))
    with pytest.raises(click.BadParameter, match=r"f/sub: .*f is a file, not a folder"):
        _convert(OutputFolder(), str(blocker / "sub"))


def test_output_file(tmp_path):
    blocker = tmp_path / "f"
    blocker.write_text("x")
    assert _convert(OutputFile(), str(blocker)) == blocker  # overwriting a file is fine
    assert _convert(OutputFile(), str(tmp_path / "new.yaml")) == tmp_path / "new.yaml"
    with pytest.raises(click.BadParameter, match="is a folder, not a file"):
        _convert(OutputFile(), str(tmp_path))
    with pytest.raises(click.BadParameter, match="f is a file, not a folder"):
        _convert(OutputFile(), str(blocker / "p.yaml"))


@pytest.mark.parametrize("good", ["tcp://10.0.0.5:8786", "localhost:8786", "tls://[::1]:8786",
                                  "tcp://sched.example.com:1"])
def test_scheduler_address_good(good):
    assert _convert(SchedulerAddress(), good) == good


@pytest.mark.parametrize("bad", ["cluster", "tcp://host", "host:", "tcp://host:0",
                                 "tcp://host:70000", "tcp://:8786", "host:port"])
def test_scheduler_address_bad(bad):
    with pytest.raises(click.BadParameter, match="not a scheduler address"):
        _convert(SchedulerAddress(), bad)


def test_usage_error_line_names_command_and_option():
    @click.group()
    def top() -> None:
        pass

    @top.command()
    @click.option("--budget", "-b", type=Integer(1))
    def tune(budget: int) -> None:
        pass

    ctx = click.Context(tune, info_name="tune", parent=click.Context(top, info_name="x"))
    err = click.BadParameter("'x' is not a valid integer.", ctx=ctx, param=tune.params[0])
    assert usage_error_line(err) == "rvmsim tune: --budget: 'x' is not a valid integer"
    assert usage_error_line(click.UsageError("Missing command.")) == "rvmsim: missing command"
