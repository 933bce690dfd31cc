"""Each benchmark record's makespan lower bound, computed from its scene when a report is
made (``lamp.scene.bounds``), so that every run in a report is measured against one and the
same bound, however old its record.

A record names its scene by ``scene_file`` (a scene file, for a folder suite) or by
``scene`` (a built-in suite scene); :func:`record_scene` loads it. A lifelong run's bound
covers its tasks as they were released in that run (``scene.tasks.chain_lower_bound``),
so its recorded bound is kept; so is the bound of a record whose scene cannot be found
any more.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from lamp.scene.bounds import makespan_lower_bound
from lamp.scene.loader import SceneError, load_scene
from lamp.scene.model import Scene
from lamp.suites import resolve_scene

__all__ = ["record_scene", "with_scene_bounds"]


def record_scene(rec: dict[str, Any]) -> Scene:
    """The scene of a results record: its ``scene_file`` when that is a file, else the
    built-in scene named ``scene`` (``SceneError`` when neither is found)."""
    path = Path(rec.get("scene_file") or "")
    return load_scene(path) if path.is_file() else resolve_scene(rec["scene"])


def with_scene_bounds(records: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """``records`` (copies) with ``makespan_lower_bound_s`` computed from each one's scene
    (once per scene) and ``makespan_over_bound`` from it and ``makespan_s``, except for
    lifelong runs and records whose scene is not found (module docstring)."""
    bounds: dict[tuple[str, str], float | None] = {}
    out = []
    for rec in records:
        rec = dict(rec)
        out.append(rec)
        if rec.get("tasks"):
            continue
        key = (str(rec.get("scene_file") or ""), str(rec.get("scene")))
        if key not in bounds:
            try:
                bounds[key] = makespan_lower_bound(record_scene(rec)).seconds
            except (SceneError, OSError, KeyError):
                bounds[key] = None
        bound = bounds[key]
        if bound is None:
            continue
        rec["makespan_lower_bound_s"] = round(bound, 6)
        makespan = rec.get("makespan_s")
        rec["makespan_over_bound"] = (round(float(makespan) / bound, 4)
                                      if makespan is not None and bound > 0 else None)
    return out
