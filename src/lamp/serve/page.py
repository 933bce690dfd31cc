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

from importlib import resources
from typing import Any

from lamp.geometry.shapes import half_extents
from lamp.scene.model import Scene
from lamp.viz.replay_html import inline_page, shape_payload
from lamp.viz.replay_options import RenderOptions
from lamp.viz.scene_plot import GOAL_COLOR, OBSTACLE_COLOR, ROBOT_COLOR, object_color

__all__ = ["live_page", "scene_payload"]


def scene_payload(scene: Scene) -> dict[str, Any]:
    """What the page needs of ``scene`` (the JSON in ``#lamp-data``)."""
    return {
        "title": f"lamp serve - {scene.name}",
        "workspace": [float(v) for v in scene.workspace],
        "robot_radius": float(scene.robot_radius),
        "min_robot_px": float(RenderOptions().min_robot_px),
        "robots": scene.robot_starts_array.round(6).tolist(),
        "obstacles": [shape_payload(o.shape, o.pose) for o in scene.obstacles],
        "objects": [{**shape_payload(o.shape, None), "color": object_color(k),
                     "start": [float(v) for v in o.start],
                     "tick": float(half_extents(o.shape)[0])}
                    for k, o in enumerate(scene.objects)],
        "colors": {"robot": ROBOT_COLOR, "goal": GOAL_COLOR, "obstacle": OBSTACLE_COLOR},
    }


def _asset(name: str) -> str:
    return (resources.files("lamp.serve") / "static" / name).read_text(encoding="utf-8")


def live_page(scene: Scene) -> str:
    """The live page for ``scene`` (module docstring; ``replay_html.inline_page``)."""
    return inline_page(_asset("live.html"), f"lamp serve - {scene.name}", _asset("live.css"),
                       _asset("live.js"), scene_payload(scene), "live.js")
