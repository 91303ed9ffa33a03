"""Bad ISP params files (issue #14, groups 1 and 2), YAML and JSON: huge integers, NaN and
infinities, RVM output sizes over the limits, and files over the YAML limits."""

from __future__ import annotations

import pytest

from .bombs import BOMBS
from .conftest import SMALL_SCENE
from .harness import MEMORY, Case, check_case

P_YAML, P_JSON = "p.yaml", "p.json"


def _process(name: str) -> tuple[str, ...]:
    return ("process", SMALL_SCENE, "--params", name, "--out", "o", "--no-progress")


def _file(name: str, text: str):
    return lambda folder: (folder / name).write_text(text)


BIG = "9" * 400
#: (case id, file name, text, key or word named)
FILES = [
    ("rad-400-digits", P_YAML, f"rad: {BIG}\n", "rad"),
    ("rad-negative-400-digits", P_YAML, f"rad: -{BIG}\n", "rad"),
    ("rad-nan", P_YAML, "rad: .nan\n", "rad"),
    ("zoom-inf", P_YAML, "zoom: .inf\n", "zoom"),
    ("fov-minus-inf", P_YAML, "fov: -.inf\n", "fov"),
    ("size-huge", P_YAML, "output: {size: [100000, 100000]}\n", "output.size"),
    ("size-pixels", P_YAML, "output: {size: [8192, 8192]}\n", "output.size"),
    ("size-400-digits", P_YAML, f"output: {{size: [{BIG}, 100]}}\n", "output.size"),
    ("size-tiny", P_YAML, "output: {size: [4, 4]}\n", "output.size"),
    ("json-rad-400-digits", P_JSON, f'{{"rad": {BIG}}}', "rad"),
    ("json-rad-1e400", P_JSON, '{"rad": 1e400}', "rad"),
    ("json-nan", P_JSON, '{"zoom": NaN}', "zoom"),
    ("json-deep", P_JSON, "[" * 100000 + "]" * 100000, "nested"),
    ("json-size-huge", P_JSON, '{"output": {"size": [100000, 100000]}}', "output.size"),
    ("json-huge-file", P_JSON, '{"rad": 600' + " " * (5 * 1024**2) + "}", "limit"),
]
#: Cases run in a child of their own: RVM images over the pixel limit.
ISOLATED = {"size-huge": MEMORY, "size-pixels": MEMORY, "json-size-huge": MEMORY}
CASES = [Case(f"params-{i}", _process(name), (name, key), _file(name, text),
              isolate=ISOLATED.get(i, "")) for i, name, text, key in FILES]
CASES += [Case(f"params-yaml-{i}", _process(P_YAML), (P_YAML, "limit"),
               _file(P_YAML, "rad: 600\n" + text), isolate=why)
          for i, text, why in BOMBS]
CASES += [
    Case("params-evaluate-rad-400-digits",
         ("evaluate", SMALL_SCENE, "--params", P_YAML, "--out", "e", "--no-progress"),
         (P_YAML, "rad"), _file(P_YAML, f"rad: {BIG}\n")),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_params_file(case, case_dir):
    check_case(case, case_dir)
