"""The package's layers depend one way: scene -> geometry, never geometry -> scene.

Checked twice: statically (no module of ``lamp.geometry`` imports ``lamp.scene`` or a layer
above it outside ``if TYPE_CHECKING:``) and by importing leaf modules in a fresh
interpreter and looking at what got loaded.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "lamp"
#: What each layer may import from lamp (besides itself).
ALLOWED = {
    "geometry": set(),
}
LAYERS = ("geometry", "scene", "sim", "manip", "mrmp", "search", "planners", "suites",
          "bench", "viz")


def _runtime_imports(path: Path) -> set[str]:
    """The lamp modules ``path`` imports when it runs (TYPE_CHECKING blocks excluded)."""
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
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return {m for m in found if m == "lamp" or m.startswith("lamp.")}


@pytest.mark.parametrize("layer", sorted(ALLOWED))
def test_layer_imports_only_what_it_may(layer):
    bad = []
    for path in sorted((SRC / layer).rglob("*.py")):
        for module in _runtime_imports(path):
            parts = module.split(".")
            other = parts[1] if len(parts) > 1 else ""
            if other != layer and other not in ALLOWED[layer]:
                bad.append(f"{path.relative_to(SRC)} imports {module}")
    assert not bad, "\n".join(bad)


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
