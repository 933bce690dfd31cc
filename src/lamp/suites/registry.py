"""The built-in benchmark suites shipped with the package (``src/lamp/suites/data``).

Each suite is a folder ``data/<name>/`` of scene files ``<name>-NN.yaml`` plus a
``manifest.json`` written by ``scripts/generate_suites.py`` (file hashes, generator
settings and the check results of every scene: routes, clearances, robot reachability).

>>> from lamp.suites import list_suites, suite_scenes
>>> list_suites()
['random', 'maze', 'tilt', 'warehouse', 'iros', 'warehouse-xl', 'corridor', 'fleet',
 'lifelong']
>>> len(suite_scenes("maze"))
25
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from lamp.scene.loader import SceneError, load_scene
from lamp.scene.model import Scene

#: The file beside a suite's scene files that records their hashes and generator.
MANIFEST_FILE = "manifest.json"

DATA_DIR = Path(str(resources.files("lamp.suites") / "data"))


@dataclass(frozen=True)
class SuiteInfo:
    """Name, one-line description and expected number of scenes of a suite.

    ``paper``: the suite is one of the LAMP paper's benchmarks (the four families and
    IROS), so the benchmark runs it under the paper's settings (``PAPER_MAX_SEGMENTS``
    executed segments per object); the other built-in suites get the limit that scales
    with the task, as user scenes do (``lamp.planners.config.segment_limit``).
    """

    name: str
    description: str
    n_scenes: int
    paper: bool = True


SUITES: dict[str, SuiteInfo] = {
    s.name: s
    for s in (
        SuiteInfo("random", "sparse scattered circles and boxes (LAMP paper: Random)", 25),
        SuiteInfo(
            "maze", "corridor maze with roomy and object-tight corridors (LAMP paper: Maze)", 25
        ),
        SuiteInfo(
            "tilt", "blocks at oblique angles forming diagonal channels (LAMP paper: Tilt)", 25
        ),
        SuiteInfo(
            "warehouse",
            "shelf rows, pallets, cargo and traffic barriers (LAMP paper: Warehouse)",
            25,
        ),
        SuiteInfo(
            "iros",
            "9 objects moved one by one to spell I R O S (LAMP paper: long-horizon case study)",
            1,
        ),
        SuiteInfo(
            "warehouse-xl",
            "20-50 m halls: shelf rows, aisles, cross-aisles and pallets; 20-70 m routes",
            25,
            paper=False,
        ),
        SuiteInfo(
            "corridor",
            "6-14 m maps: one corridor 2-6 cm wider than the load, 1-4 oblique turns "
            "with turning bays",
            25,
            paper=False,
        ),
        SuiteInfo(
            "fleet",
            "6-50 m maps, 2-12 objects, 6-24 robots, concurrent schedule: rooms, aisles, "
            "yards, door swaps, blockers cleared first",
            25,
            paper=False,
        ),
        SuiteInfo(
            "lifelong",
            "fleet maps of 6-17 m, 20 tasks released while the robots work (Poisson "
            "arrivals), loads shuttled between their stations",
            10,
            paper=False,
        ),
    )
}


def list_suites() -> list[str]:
    """Names of the built-in suites: the paper's, in its order, then the others."""
    return list(SUITES)


def suite_info(name: str) -> SuiteInfo:
    """Description of suite ``name``; ValueError listing the valid names when unknown."""
    try:
        return SUITES[name]
    except KeyError:
        raise ValueError(f"unknown suite {name!r}; valid names: {', '.join(SUITES)}") from None


def suite_dir(name: str) -> Path:
    """Folder holding the suite's scene files and manifest."""
    suite_info(name)
    return DATA_DIR / name


def suite_files(name: str) -> list[Path]:
    """The suite's scene files, sorted by name."""
    return sorted(suite_dir(name).glob(f"{name}-*.yaml"))


def suite_scenes(name: str) -> list[Scene]:
    """Load (and validate) every scene of suite ``name``, sorted by name."""
    return [load_scene(p) for p in suite_files(name)]


def suite_manifest(name: str) -> dict[str, Any]:
    """The suite's manifest (see ``scripts/generate_suites.py``)."""
    with open(suite_dir(name) / MANIFEST_FILE, encoding="utf-8") as f:
        return json.load(f)


def export_suite(name: str, directory: str | Path) -> list[Path]:
    """Copy the suite's scene files and manifest into ``directory`` (created if needed);
    returns the written paths."""
    src = suite_dir(name)
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for p in [*suite_files(name), src / MANIFEST_FILE]:
        dst = out / p.name
        shutil.copyfile(p, dst)
        written.append(dst)
    return written


def sha256_of(path: str | Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


# --------------------------------------------------------------------------- writing
def _num(v: Any) -> str:
    """A YAML number: ``repr`` of the float (shortest round-trip form, always with a dot
    or exponent), integers as floats so that the file reads back as floats."""
    f = float(v)
    if f == 0.0:
        f = 0.0
    text = repr(f)
    if "e" in text and "." not in text.split("e")[0]:
        m, e = text.split("e")
        text = f"{m}.0e{e}"
    return text


def _flow(v: Any) -> str:
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}: {_flow(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_flow(x) for x in v) + "]"
    if isinstance(v, str):
        return v
    return _num(v)


def scene_yaml(d: dict[str, Any]) -> str:
    """Deterministic, readable YAML text of a scene-file dict (obstacles one per line;
    ``schedule`` when given, objects' ``after`` lists as integers)."""
    lines = [
        f"format: {d['format']}",
        f"name: {d['name']}",
        f"workspace: {_flow(d['workspace'])}",
        *([f"schedule: {d['schedule']}"] if d.get("schedule") else []),
        "robots:",
        f"  radius: {_num(d['robots']['radius'])}",
        "  starts:",
    ]
    lines += [f"    - {_flow(p)}" for p in d["robots"]["starts"]]
    if d.get("obstacles"):
        lines.append("obstacles:")
        lines += [f"  - {_flow(o)}" for o in d["obstacles"]]
    lines.append("objects:")
    for o in d["objects"]:
        first = True
        for k, v in o.items():
            prefix = "  - " if first else "    "
            # object indices stay integers (every other number is written as a float)
            text = "[" + ", ".join(str(int(i)) for i in v) + "]" if k == "after" else _flow(v)
            lines.append(f"{prefix}{k}: {text}")
            first = False
    if d.get("tasks"):
        lines.append("tasks:")
        lines += [f"  - {{object: {int(t['object'])}, goal: {_flow(t['goal'])}, "
                  f"release_s: {_num(t['release_s'])}}}" for t in d["tasks"]]
    return "\n".join(lines) + "\n"


_SUITE_SCENE = re.compile(r"^(?P<suite>[a-z][a-z-]*)-(?P<index>\d+)$")


def resolve_scene(scene: Scene | str | Path) -> Scene:
    """A ``Scene``: given as is, loaded from a scene file, or a built-in suite scene by name
    (``"maze-07"``, as ``lamp suite list`` names the suites).

    Raises:
        SceneError: the file is invalid (message from ``load_scene``), or ``scene`` is
            neither an existing file nor a built-in scene name (the message names it and
            lists the suites).
    """
    if isinstance(scene, Scene):
        return scene
    if not isinstance(scene, (str, Path)):
        raise SceneError(
            f"scene must be a Scene, a scene file path or a suite scene name, got {scene!r}"
        )
    path = Path(scene)
    if path.exists():
        return load_scene(path)
    match = _SUITE_SCENE.match(str(scene))
    if match and match["suite"] in SUITES:
        for candidate in suite_files(match["suite"]):
            if candidate.stem == str(scene):
                return load_scene(candidate)
    try:
        return load_scene(path)  # raises the loader's own "file not found"
    except SceneError as exc:
        raise SceneError(
            f"{exc}; unknown scene {str(scene)!r}: no built-in suite scene of that name "
            f"either (suite scenes are named like 'maze-07'; suites: {', '.join(SUITES)})",
            path=exc.path, field=exc.field, reason=exc.reason) from None
