"""The package's house rules (issue #13), checked on the source itself.

- no module over 500 lines;
- no function over 80 lines unless a comment ``# long: <reason>`` stands on its ``def`` line
  or the line after it;
- no import of a private name (``_x``) from another package of rvmsim;
- no silent ``except``: a handler whose body is only ``pass`` / ``...`` / ``continue`` with no
  comment saying why the error is expected there;
- data flows one way between the stages (:data:`LAYERS`);
- imports of rvmsim's own modules stand at module top, outside ``cli/`` (whose commands
  import their stage on use, so ``rvmsim --help`` stays fast): a function-level import
  hides a dependency, and often a circle;
- no import circle between the files of one package (``if TYPE_CHECKING:`` imports aside).

Function length counts the lines from ``def`` to the end, less the docstring.
"""

from __future__ import annotations

import ast
import graphlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "rvmsim"
MODULES = sorted(ROOT.rglob("*.py"))
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 80
#: Private top-level modules every package may use (helpers below all the stages).
_SHARED = ("rvmsim._io", "rvmsim._optional", "rvmsim._procs", "rvmsim._progress",
           "rvmsim._version")


def _package(path: Path) -> str:
    rel = path.relative_to(ROOT)
    return rel.parts[0] if len(rel.parts) > 1 else ""


def _resolve(path: Path, node: ast.ImportFrom) -> str:
    """The absolute dotted module an ``ImportFrom`` names."""
    if node.level == 0:
        return node.module or ""
    parts = ["rvmsim", *path.relative_to(ROOT).with_suffix("").parts]
    base = parts[: len(parts) - node.level]
    return ".".join(base + ([node.module] if node.module else []))


def _functions(tree: ast.AST) -> list[ast.FunctionDef | ast.AsyncFunctionDef]:
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_module_size(path: Path) -> None:
    n = len(path.read_text(encoding="utf-8").splitlines())
    assert n <= MAX_MODULE_LINES, f"{path.name}: {n} lines (limit {MAX_MODULE_LINES})"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_function_length(path: Path) -> None:
    lines = path.read_text(encoding="utf-8").splitlines()
    long = []
    for fn in _functions(ast.parse("\n".join(lines))):
        n = (fn.end_lineno or fn.lineno) - fn.lineno + 1
        first = fn.body[0]
        if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(
                first.value.value, str):
            n -= (first.end_lineno or first.lineno) - first.lineno + 1
        head = " ".join(lines[fn.lineno - 1: fn.lineno + 1])
        if n > MAX_FUNCTION_LINES and "# long:" not in head:
            long.append(f"{fn.name} ({n} lines)")
    assert not long, f"{path.name}: functions over {MAX_FUNCTION_LINES} lines: {long}"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_private_import_across_packages(path: Path) -> None:
    own = _package(path)
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.ImportFrom):
            continue
        target = _resolve(path, node)
        if not target.startswith("rvmsim"):
            continue
        tparts = target.split(".")
        target_pkg = tparts[1] if len(tparts) > 2 or (
            len(tparts) == 2 and (ROOT / tparts[1]).is_dir()) else ""
        if target_pkg == own:
            continue
        private_module = any(p.startswith("_") and p != "__init__" for p in tparts[1:])
        for alias in node.names:
            if (alias.name.startswith("_") or private_module) and target not in _SHARED:
                bad.append(f"{target}.{alias.name} (line {node.lineno})")
    assert not bad, f"{path.name}: private names imported from other packages: {bad}"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_silent_except(path: Path) -> None:
    silent = []
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ExceptHandler):
            body = node.body
            quiet = all(isinstance(s, (ast.Pass, ast.Continue)) or (
                isinstance(s, ast.Expr) and isinstance(s.value, ast.Constant)) for s in body)
            said = any("#" in line for line in lines[node.lineno - 1: node.end_lineno])
            if quiet and not said:
                silent.append(f"line {node.lineno}")
    assert not silent, f"{path.name}: except blocks that swallow the error silently: {silent}"


def test_the_checks_see_violations(tmp_path: Path) -> None:
    """The AST checks above do find what they look for (so they cannot pass vacuously)."""
    src = "def f():\n" + "    x = 1\n" * 90 + "try:\n    f()\nexcept OSError:\n    pass\n"
    tree = ast.parse(src)
    assert max((f.end_lineno or 0) - f.lineno + 1 for f in _functions(tree)) > 80
    handlers = [n for n in ast.walk(tree) if isinstance(n, ast.ExceptHandler)]
    assert handlers and isinstance(handlers[0].body[0], ast.Pass)
    node = ast.parse("from ..tune.loop import _chunks").body[0]
    assert isinstance(node, ast.ImportFrom)
    assert _resolve(ROOT / "batch" / "point.py", node) == "rvmsim.tune.loop"


#: The stages from the bottom up: a module may import from its own stage and those below it
#: (imports under ``if TYPE_CHECKING:`` are for annotations only and do not count).
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "labels", "_io", "_optional", "_procs", "_progress", "_version", "storage"),
    ("camera",),
    ("scene",),
    ("render", "isp"),
    ("pose",),
    ("compensation",),
    ("criteria",),
    ("regulations",),
    ("guidelines",),
    ("pipeline", "markets"),
    ("percar",),
    ("robust",),
    ("search",),
    ("runs",),
    ("tune",),
    ("batch", "validate", "calibrate", "eol"),
    ("report",),
    ("console",),
    ("testing",),  # what tests and benchmarks share: nothing in the product imports it
    ("cli", "__main__", "__init__"),
)
_LAYER = {name: k for k, names in enumerate(LAYERS) for name in names}


def _runtime_imports(tree: ast.AST) -> list[ast.ImportFrom]:
    """``from … import`` statements outside ``if TYPE_CHECKING:`` blocks."""
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip |= {id(n) for stmt in node.body for n in ast.walk(stmt)}
    return [n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and id(n) not in skip]


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_data_flows_one_way(path: Path) -> None:
    rel = path.relative_to(ROOT)
    own = rel.parts[0] if len(rel.parts) > 1 else rel.stem
    upward = []
    for node in _runtime_imports(ast.parse(path.read_text(encoding="utf-8"))):
        target = _resolve(path, node).split(".")
        if target[0] != "rvmsim" or len(target) < 2:
            names = [a.name for a in node.names] if target == ["rvmsim"] else []
            stages = [n for n in names if n in _LAYER]
        else:
            stages = [target[1]]
        for stage in stages:
            if _LAYER[stage] > _LAYER[own]:
                upward.append(f"{stage} (line {node.lineno})")
    assert not upward, f"{rel}: imports from stages above {own}: {upward}"


def test_the_layer_check_sees_an_upward_import() -> None:
    tree = ast.parse("from ..batch import task_malloc\nif TYPE_CHECKING:\n    from ..cli import x\n")
    found = _runtime_imports(tree)
    assert [_resolve(ROOT / "tune" / "run.py", n) for n in found] == ["rvmsim.batch"]
    assert _LAYER["batch"] > _LAYER["tune"]


def _module_name(path: Path) -> str:
    parts = ["rvmsim", *path.relative_to(ROOT).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


_MODULE_NAMES = {_module_name(p) for p in MODULES}


def _imported_modules(path: Path, tree: ast.AST, names: set[str] = _MODULE_NAMES) -> set[str]:
    """The modules of ``names`` that ``tree`` (of ``path``) imports at run time (``from . import
    x`` counts as module ``x`` when ``x`` is one)."""
    found = set()
    for node in _runtime_imports(tree):
        target = _resolve(path, node)
        if path.name == "__init__.py" and node.level:
            target = _resolve(path.with_name("x.py"), node)  # a package's own level
        for alias in node.names:
            if f"{target}.{alias.name}" in names:
                found.add(f"{target}.{alias.name}")
            elif target in names:
                found.add(target)
    return found


#: Modules whose imports of rvmsim are deferred by design: the command line (each command
#: imports what it runs; its entry point starts the worker fork server before it imports
#: the command group).
_DEFERRED = [p for p in MODULES if _package(p) == "cli"]


@pytest.mark.parametrize("path", [p for p in MODULES if p not in _DEFERRED],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_own_imports_at_module_top(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    inner = []
    for fn in _functions(tree):
        for node in ast.walk(fn):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith(
                    "rvmsim")):
                inner.append(f"{_resolve(path, node)} (line {node.lineno})")
            elif isinstance(node, ast.Import) and any(a.name.split(".")[0] == "rvmsim"
                                                      for a in node.names):
                inner.append(f"rvmsim (line {node.lineno})")
    assert not inner, f"{path.relative_to(ROOT)}: function-level imports of rvmsim: {inner}"


def _package_circle(package: str, sources: dict[Path, str]) -> list[str] | None:
    """An import circle between the files of ``package`` (``sources``: path → text; the
    package's ``__init__`` aside, as it gathers the package's names from every file), or
    None."""
    prefix = f"rvmsim.{package}."
    names = {_module_name(p) for p in sources}
    graph: dict[str, set[str]] = {}
    for path, text in sources.items():
        if _package(path) != package or path.name == "__init__.py":
            continue
        name = _module_name(path)
        deps = _imported_modules(path, ast.parse(text), names)
        graph[name] = {d for d in deps if d.startswith(prefix) and d != name
                       and not (ROOT / d.removeprefix("rvmsim.").replace(".", "/")).is_dir()}
    try:
        tuple(graphlib.TopologicalSorter(graph).static_order())
    except graphlib.CycleError as err:
        return list(err.args[1])
    return None


@pytest.mark.parametrize("package", sorted({_package(p) for p in MODULES} - {""}))
def test_no_import_circle_inside_a_package(package: str) -> None:
    circle = _package_circle(package, {p: p.read_text(encoding="utf-8") for p in MODULES})
    assert circle is None, f"{package}: import circle {' -> '.join(circle or [])}"


def test_the_circle_check_sees_a_circle() -> None:
    """A circle through ``from . import``, ``from .x import``, and not through TYPE_CHECKING."""
    scene = ROOT / "scene"
    files = {scene / "a.py": "from . import b\n", scene / "b.py": "from .c import y\n",
             scene / "c.py": "if TYPE_CHECKING:\n    from .a import z\n"}
    assert _package_circle("scene", files) is None
    files[scene / "c.py"] = "import numpy\nfrom .a import z\n"
    assert sorted(set(_package_circle("scene", files) or [])) == [
        "rvmsim.scene.a", "rvmsim.scene.b", "rvmsim.scene.c"]
