"""The live page of ``lamp serve`` (``GET /``): one HTML file with its stylesheet, script and
the scene inlined; what moves comes from the service's server-sent events.

It draws as the replay viewer (``lamp.viz.replay_html``) does, with the same colours:
the workspace, obstacles, objects at their live poses with a heading tick, robots as
disks, and each object's next goals (solid: its active task's, dashed: its next queued
one's). The panel lists the tasks (newest first) and has a form to post one; a click on
the map fills in its x and y. The page references nothing outside itself but the
service's own ``events`` and ``tasks``.
"""

from __future__ import annotations

import html
import json
from importlib import resources
from typing import Any

import numpy as np

from lamp.geometry.shapes import half_extents, local_outline, world_outline
from lamp.scene.model import Circle, Scene, Shape
from lamp.viz.replay_options import RenderOptions
from lamp.viz.scene_plot import GOAL_COLOR, OBSTACLE_COLOR, ROBOT_COLOR, object_color

__all__ = ["PLACEHOLDERS", "live_page", "scene_payload"]

#: Placeholders of live.html that :func:`live_page` replaces, in this order.
PLACEHOLDERS = ("__LAMP_TITLE__", "__LAMP_CSS__", "__LAMP_JS__", "__LAMP_DATA__")


def _shape(shape: Shape, pose: Any | None) -> dict[str, Any]:
    """A circle as its radius (its centre ``at`` for an obstacle), else its outline: in
    the world for an obstacle (``pose`` given), in the shape's own frame otherwise."""
    if isinstance(shape, Circle):
        d: dict[str, Any] = {"circle": float(shape.radius)}
        if pose is not None:
            d["at"] = [float(pose[0]), float(pose[1]), 0.0]
        return d
    pts = local_outline(shape) if pose is None else world_outline(shape, pose)
    return {"outline": np.asarray(pts, float).round(6).tolist()}


def scene_payload(scene: Scene) -> dict[str, Any]:
    """What the page needs of ``scene`` (the JSON in ``#lamp-data``)."""
    return {
        "title": f"lamp serve - {scene.name}",
        "workspace": [float(v) for v in scene.workspace],
        "robot_radius": float(scene.robot_radius),
        "min_robot_px": float(RenderOptions().min_robot_px),
        "robots": scene.robot_starts_array.round(6).tolist(),
        "obstacles": [_shape(o.shape, o.pose) for o in scene.obstacles],
        "objects": [{**_shape(o.shape, None), "color": object_color(k),
                     "start": [float(v) for v in o.start],
                     "tick": float(half_extents(o.shape)[0])}
                    for k, o in enumerate(scene.objects)],
        "colors": {"robot": ROBOT_COLOR, "goal": GOAL_COLOR, "obstacle": OBSTACLE_COLOR},
    }


def _asset(name: str) -> str:
    return (resources.files("lamp.serve") / "static" / name).read_text(encoding="utf-8")


def live_page(scene: Scene) -> str:
    """The live page for ``scene`` (module docstring)."""
    data = json.dumps(scene_payload(scene), separators=(",", ":")).replace("</", "<\\/")
    js = _asset("live.js")
    if "</script" in js.lower():
        raise RuntimeError("live.js must not contain '</script' (it is inlined)")
    parts = {"__LAMP_TITLE__": html.escape(f"lamp serve - {scene.name}"),
             "__LAMP_CSS__": _asset("live.css"), "__LAMP_JS__": js, "__LAMP_DATA__": data}
    page = _asset("live.html")
    for key in PLACEHOLDERS:  # one pass each, in order; the data goes in last
        page = page.replace(key, parts[key], 1)
    return page
