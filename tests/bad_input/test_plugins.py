"""Criteria plugins that fail (issue #30): an EC whose code raises on a real image (it
passed the load-time check on an empty 8 × 8 one), in ``evaluate`` and in ``tune``'s worker
processes, and a plugin that exits or raises a ``BaseException`` at import.  Each is one
stderr line naming the plugin, the EC and the image (or the criteria file and the plugin),
exit 2, never exit 0."""

from __future__ import annotations

import pytest

from .conftest import SMALL_SCENE
from .harness import Case, check_case

C = "c.yaml"
EVALUATE = ("evaluate", SMALL_SCENE, "--criteria", C, "--out", "e", "--no-progress")
TUNE = ("tune", SMALL_SCENE, "--criteria", C, "--out", "new", "--strategy", "random",
        "--budget", "8", "--no-progress")
EC = "acme-breaks"

#: An EC that works on the load-time check's empty 8 × 8 image and raises ``RAISE`` on a
#: real one: in every process, or (``WORKER_ONLY``) only in a pool's worker processes.
PLUGIN = '''
import multiprocessing

from rvmsim.criteria import EcDefinition


class Boom(BaseException):
    pass


def measure(src, options):
    if src.shape[0] > 8 and (not WORKER_ONLY or multiprocessing.parent_process() is not None):
        raise RAISE
    return 1.0


def annotate(canvas, item, detail):
    if ANNOTATE:
        raise RAISE


ECS = [EcDefinition(id="acme-breaks", name="breaks", unit="", groups=(), measure=measure,
                    annotate=annotate)]
'''


def _plugin(raise_: str, *, worker_only: bool = False, annotate: bool = False) -> str:
    return (f"WORKER_ONLY = {worker_only}\nANNOTATE = {annotate}\n"
            + PLUGIN.replace("raise RAISE", f"raise {raise_}"))


#: (case id, command, plugin source, EC named)
MEASURE = [
    ("measure-valueerror", EVALUATE, _plugin("ValueError('no board here')"), True),
    ("measure-systemexit", EVALUATE, _plugin("SystemExit(0)"), True),
    ("measure-baseexception", EVALUATE, _plugin("Boom('past except Exception')"), True),
    ("annotate-raises", EVALUATE, _plugin("ZeroDivisionError('x')", annotate=True)
     .replace("src.shape[0] > 8", "False"), True),
    ("tune-measure-raises", TUNE + ("--workers", "1"), _plugin("KeyError('k')"), True),
    ("tune-measure-raises-in-workers", TUNE + ("--workers", "2"),
     _plugin("ValueError('only in a worker')", worker_only=True), True),
    ("import-sys-exit-0", EVALUATE, "import sys\nsys.exit(0)\n", False),
    ("import-sys-exit-none", TUNE, "raise SystemExit\n", False),
    ("import-baseexception", EVALUATE,
     "class Boom(BaseException):\n    pass\n\n\nraise Boom('at import')\n", False),
    ("import-generatorexit", EVALUATE, "raise GeneratorExit\n", False),
    ("ecs-getattr-raises", EVALUATE,
     "def __getattr__(name):\n    raise RuntimeError('no ' + name)\n", False),
    ("ecs-getattr-exits", TUNE, "def __getattr__(name):\n    raise SystemExit(0)\n", False),
]


@pytest.mark.parametrize("case_id, args, source, names_ec", MEASURE,
                         ids=[m[0] for m in MEASURE])
def test_a_failing_plugin_is_one_line(case_id, args, source, names_ec, case_dir,
                                      plugin_module):
    module = plugin_module(source)
    (case_dir / C).write_text(f"plugins: [{module}]\n")
    names = (module, EC, SMALL_SCENE) if names_ec else (C, module)
    out = check_case(Case(case_id, args, names), case_dir)
    assert not (case_dir / "e" / "ec.json").exists(), out.stderr
