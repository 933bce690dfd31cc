"""The package's layers depend one way, downward; no module imports itself in a circle.

The layers, bottom to top (``LAYERS``): what a module of one layer may import at run time is
its own layer and the layers below (``if TYPE_CHECKING:`` imports excepted). The command
line, the ``lamp.cli`` package and nothing else, is the top layer. Checked statically over
every module, and by importing leaf modules in a fresh interpreter and looking at what got
loaded. Also: no import cycle among the modules, no module over ``MAX_LINES`` lines and no
function over ``MAX_FUNCTION_LINES``.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "lamp"
#: Bottom to top; a package (or top-level module) per name, several per layer where they
#: are peers that do not import each other.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "lazy_exports", "io", "progress"),
    ("geometry",),
    ("contract",),
    ("scene",),
    ("sim",),
    ("record", "mrmp", "search"),
    ("manip",),
    ("suites",),
    ("viz",),
    ("env",),
    ("rl",),
    ("planners",),
    ("baselines",),
    ("fleet",),
    ("pipeline",),
    ("bench", "serve"),
    ("demo",),
    ("cli",),  # the command line: parses, loads, calls, writes; may import any layer
)
#: The package root: its top-level names load their modules lazily (``lamp.lazy_exports``).
ROOT = "lamp"
MAX_LINES = 500
LEVEL = {name: i for i, names in enumerate(LAYERS) for name in names}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(SRC.rglob("*.py"))}


def _runtime_imports(path: Path) -> set[str]:
    """The lamp modules ``path`` imports when it runs (TYPE_CHECKING blocks excluded):
    for ``from a.b import c`` both ``a.b`` and, when it is a module, ``a.b.c``; a bare
    ``import lamp`` (the package root, loaded first by any import) is not counted."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    skipped: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skipped.update(id(n) for n in ast.walk(node))
    found: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skipped:
            continue
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names
                         if f"{node.module}.{a.name}" in MODULES)
        elif isinstance(node, ast.Import):  # a bare ``import lamp`` reads the version only
            found.update(a.name for a in node.names if a.name != "lamp")
    return {m for m in found if m == "lamp" or m.startswith("lamp.")}


def _all_imports(path: Path) -> set[str]:
    """Every module ``path`` names in an import statement, wherever the statement is."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return found


def _layer(module: str) -> int | None:
    """The layer of a lamp module; None for the package root (in no layer)."""
    if module == ROOT:
        return None
    return LEVEL[module.split(".")[1]]


def test_every_package_has_a_layer():
    tops = {m.split(".")[1] for m in MODULES if m != ROOT}
    assert tops - set(LEVEL) == set()


def test_the_command_line_is_the_cli_package_alone():
    """Every command lives in ``lamp.cli``: no ``cli`` module elsewhere, and nothing below
    the top layer imports typer."""
    assert [m for m in MODULES if m.endswith(".cli") and m != "lamp.cli"] == []
    typer_users = [m for m, p in MODULES.items() if _layer(m) != LEVEL["cli"]
                   and "typer" in {n.split(".")[0] for n in _all_imports(p)}]
    assert typer_users == []


def test_layers_import_only_downward():
    bad = []
    for module, path in MODULES.items():
        mine = _layer(module)
        if mine is None:
            continue
        for target in _runtime_imports(path):
            theirs = _layer(target)
            if theirs is None or theirs > mine:
                bad.append(f"{module} (layer {mine}) imports {target} (layer {theirs})")
    assert not bad, "\n".join(bad)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_cycle_finder_finds_cycles():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    graph = {m: {t for t in _runtime_imports(p) if t in MODULES and t != m and t != ROOT}
             for m, p in MODULES.items()}
    assert _cycles(graph) == []


def test_no_module_is_too_long():
    long = {m: n for m, p in MODULES.items()
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert long == {}


#: Longest function, signature and docstring included: "about 80" lines of code; the few
#: over 80 are compiled kernels kept in one piece and ``plan_paths``, whose 60-line
#: docstring is its interface's documentation.
MAX_FUNCTION_LINES = 100


def test_no_function_is_too_long():
    long = []
    for module, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long.append(f"{module}.{node.name}: {n} lines")
    assert long == []


def test_the_static_check_sees_imports(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("from typing import TYPE_CHECKING\nimport lamp.sim\n"
                 "if TYPE_CHECKING:\n    from lamp.scene.model import Scene\n"
                 "def g():\n    from lamp.viz import x\n")
    assert _runtime_imports(f) == {"lamp.sim", "lamp.viz"}


def _loaded_after(statement: str) -> list[str]:
    code = f"import sys, json\n{statement}\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_importing_se2_loads_no_scene_format_dependencies():
    loaded = _loaded_after("import lamp.geometry.se2")
    assert not [m for m in loaded if m.startswith(("yaml", "shapely", "lamp.scene.loader"))]


def test_importing_the_robot_space_loads_no_scene_layer():
    # (Numba itself loads YAML for its configuration file: not checked here.)
    loaded = _loaded_after("import lamp.geometry.robot_space, lamp.geometry.object_space")
    assert "lamp.scene.loader" not in loaded


def test_top_level_names_resolve_lazily():
    loaded = _loaded_after("import lamp\nassert callable(lamp.load_scene)\n"
                           "assert issubclass(lamp.SceneError, Exception)")
    assert "lamp.scene.loader" in loaded
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        import lamp

        lamp.nope  # noqa: B018
