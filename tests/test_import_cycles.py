"""No two modules of the package import each other, even through ``if TYPE_CHECKING:``
imports: a circle hidden from the interpreter is still a circle in the design."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components

SRC = Path(__file__).resolve().parents[1] / "src"


def _modules() -> dict[str, Path]:
    out = {}
    for p in sorted((SRC / "lamp").rglob("*.py")):
        parts = list(p.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = p
    return out


def _imports(path: Path, modules: dict[str, Path]) -> set[str]:
    """Every lamp module ``path`` names in an import, wherever the import stands
    (``from a.b import c`` names ``a.b`` and, when it is a module, ``a.b.c``)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return {m for m in found if m in modules and m != "lamp"}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The groups of more than one node that reach each other (SciPy's strongly
    connected components), sorted."""
    names = sorted(graph)
    index = {n: i for i, n in enumerate(names)}
    edges = [(index[a], index[b]) for a in names for b in graph[a] if b != a]
    if not edges:
        return []
    rows, cols = zip(*edges, strict=True)
    adj = csr_array((np.ones(len(edges)), (rows, cols)), shape=(len(names), len(names)))
    _, label = connected_components(adj, directed=True, connection="strong")
    groups: dict[int, list[str]] = {}
    for n, c in zip(names, label, strict=True):
        groups.setdefault(int(c), []).append(n)
    return sorted(g for g in groups.values() if len(g) > 1)


def test_the_cycle_finder_finds_a_circle_and_nothing_else() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
    assert cycles({"a": {"a"}}) == []


def test_no_import_circle_counting_type_checking_imports() -> None:
    modules = _modules()
    graph = {m: _imports(p, modules) - {m} for m, p in modules.items()}
    assert cycles(graph) == []
