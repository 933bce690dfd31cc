"""Loading scene files (format ``lamp-scene/1``) with validation.

PLACEHOLDER: the validating loader is being written; this version parses valid files only.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from lamp.scene.model import Circle, Obstacle, Polygon, Rectangle, Scene, SceneObject, shape_from_dict


class SceneError(ValueError):
    """A scene file or dict is invalid; the message names the file, the field and the value."""


def scene_from_dict(d: dict[str, Any], source: str | None = None) -> Scene:
    obstacles = []
    for o in d.get("obstacles") or []:
        if o["type"] == "circle":
            obstacles.append(Obstacle(Circle(float(o["radius"])), (*map(float, o["center"]), 0.0)))
        elif o["type"] == "rectangle":
            obstacles.append(Obstacle(Rectangle(tuple(map(float, o["size"]))), (*map(float, o["center"]), float(o.get("angle", 0.0)))))
        else:
            obstacles.append(Obstacle(Polygon(tuple(tuple(map(float, p)) for p in o["points"]))))
    objects = []
    for o in d["objects"]:
        shape = shape_from_dict(o)
        objects.append(SceneObject(shape, tuple(map(float, o["start"])), tuple(map(float, o["goal"]))))
    robots = d["robots"]
    return Scene(
        name=str(d["name"]),
        workspace=tuple(map(float, d["workspace"])),
        robot_starts=tuple(tuple(map(float, p)) for p in robots["starts"]),
        objects=tuple(objects),
        obstacles=tuple(obstacles),
        robot_radius=float(robots.get("radius", 0.05)),
        source=source,
    )


def load_scene(path: str | Path) -> Scene:
    path = Path(path)
    with open(path) as f:
        d = yaml.safe_load(f)
    return scene_from_dict(d, source=str(path))
