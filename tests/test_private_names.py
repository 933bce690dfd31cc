"""No module of the package takes a private name from another: a ``_name`` is its module's
own. What two modules share is public (named and documented) in the module that owns it.

Checked statically over every module of ``src/lamp``, every import statement wherever it
stands (function bodies and ``if TYPE_CHECKING:`` blocks too): ``from lamp.a import _b``,
``from lamp.a._b import c`` and ``import lamp.a._b`` are refused; a public name imported
under a private alias (``from lamp.io import atomic_output as _atomic_output``) is not
private and passes.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "lamp"


def _private(name: str) -> bool:
    """A ``_name`` (not a ``__dunder__``)."""
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _absolute(node: ast.ImportFrom, module: str, is_package: bool) -> str:
    """The module ``node`` imports from, relative imports resolved against ``module``."""
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def private_imports(path: Path, root: Path = SRC) -> list[str]:
    """The imports of ``path`` (a module of the package at ``root``) that take a private
    name or module of another lamp module, as ``"<line>: <what>"``."""
    module = _module_name(path, root)
    is_package = path.name == "__init__.py"
    bad = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            source = _absolute(node, module, is_package)
            if source.split(".")[0] != "lamp" or source == module:
                continue
            if any(_private(part) for part in source.split(".")):
                bad.append(f"{node.lineno}: from {source} import ...")
            bad += [f"{node.lineno}: from {source} import {a.name}" for a in node.names
                    if _private(a.name)]
        elif isinstance(node, ast.Import):
            bad += [f"{node.lineno}: import {a.name}" for a in node.names
                    if a.name.split(".")[0] == "lamp"
                    and any(_private(part) for part in a.name.split("."))]
    return bad


def test_no_module_imports_a_private_name_of_another():
    bad = [f"{path.relative_to(SRC.parent)}:{where}" for path in sorted(SRC.rglob("*.py"))
           for where in private_imports(path)]
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


def test_the_check_sees_each_form(tmp_path):
    """The three forms are caught, relative ones too; public names and aliases pass."""
    package = tmp_path / "lamp" / "pkg"
    package.mkdir(parents=True)
    mod = package / "mod.py"
    mod.write_text("from lamp.a import _b\nfrom lamp.a._c import d\nimport lamp.e._f\n"
                   "from ._g import h\nfrom .other import _i\n"
                   "from lamp.io import atomic_output as _atomic_output\n"
                   "from lamp.a import __version__\nimport numpy._core\n"
                   "def f():\n    from lamp.x import _y\n")
    assert private_imports(mod, tmp_path / "lamp") == [
        "1: from lamp.a import _b", "2: from lamp.a._c import ...", "3: import lamp.e._f",
        "4: from lamp.pkg._g import ...", "5: from lamp.pkg.other import _i",
        "10: from lamp.x import _y"]
