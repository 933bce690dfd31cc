"""Scene data model: objects, robots and the scene (scene format version 1).

The shapes, poses and obstacles a scene is made of are :mod:`lamp.geometry.primitives`
(re-exported here); their conventions are stated there. All classes are frozen
dataclasses; validation of user input happens in ``lamp.scene.loader``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from lamp.geometry.primitives import (
    Circle,
    Obstacle,
    Point,
    Polygon,
    Pose,
    Rectangle,
    Shape,
    shape_from_dict,
)
from lamp.geometry.team import DEFAULT_TEAM
from lamp.scene.physics import DEFAULT_PHYSICS, ObjectPhysics, Physics

__all__ = ["SCHEDULES", "Circle", "ObjectPhysics", "Obstacle", "Physics", "Point", "Polygon",
           "Pose", "Rectangle", "Scene", "SceneObject", "Shape", "Task", "shape_from_dict"]

#: How a scene's objects are moved: ``sequential`` (the paper's: one after another, in the
#: file's order, each by the whole team) or ``concurrent`` (several at once by sub-teams,
#: ``lamp.fleet``). The first is the default.
SCHEDULES = ("sequential", "concurrent")

@dataclass(frozen=True)
class SceneObject:
    """A movable object with its start and goal poses (and, optionally, its own mass and
    friction: ``lamp.scene.physics``)."""

    shape: Shape
    start: Pose
    goal: Pose
    physics: ObjectPhysics = ObjectPhysics()
    #: Indices of the objects that must be placed before this one moves (a blocker cleared
    #: before the load behind it); only the concurrent schedule reads it (the sequential
    #: one moves objects in the file's order).
    after: tuple[int, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        d = self.shape.to_dict()
        d["start"] = [float(v) for v in self.start]
        d["goal"] = [float(v) for v in self.goal]
        d.update(self.physics.to_dict())
        if self.after:
            d["after"] = [int(k) for k in self.after]
        return d


@dataclass(frozen=True)
class Task:
    """A task of a lifelong scene: from simulated time ``release_s`` on, object ``object``
    must go to ``goal``, after every earlier task of that object (release order, then the
    file's). An object's own ``goal`` is its first task, released at 0."""

    object: int
    goal: Pose
    release_s: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"object": int(self.object), "goal": [float(v) for v in self.goal],
                "release_s": float(self.release_s)}


@dataclass(frozen=True)
class Scene:
    """One manipulation problem: workspace, robots, static obstacles, objects in order."""

    name: str
    workspace: tuple[float, float]
    robot_starts: tuple[Point, ...]
    objects: tuple[SceneObject, ...]
    obstacles: tuple[Obstacle, ...] = ()
    robot_radius: float = DEFAULT_TEAM.radius
    source: str | None = field(default=None, compare=False)
    #: What the robots and loads physically are (``lamp.scene.physics``; default: the
    #: simulator's calibrated values).
    physics: Physics = DEFAULT_PHYSICS
    #: One of :data:`SCHEDULES`.
    schedule: str = "sequential"
    #: Tasks released while the robots work (:class:`Task`), beyond each object's own
    #: goal; a scene with tasks is a lifelong one (``lamp.fleet.tasks``).
    tasks: tuple[Task, ...] = ()
    #: The map's own obstacles when ``obstacles`` adds others after them (robots of other
    #: teams standing still, ``planners.team.team_scene``); None: all of them. Not part
    #: of the scene file: it lets spaces share what depends on the map alone.
    fixed: tuple[Obstacle, ...] | None = field(default=None, compare=False, repr=False)

    @property
    def fixed_obstacles(self) -> tuple[Obstacle, ...]:
        """The leading obstacles that are the map's own (the same tuple object for a scene
        and the team scenes made from it): ``fixed`` while it leads ``obstacles``, else
        every obstacle."""
        f = self.fixed
        if f is None or f is self.obstacles:
            return self.obstacles
        n = len(f)
        if n <= len(self.obstacles) and all(
                a is b for a, b in zip(f, self.obstacles[:n], strict=True)):
            return f
        return self.obstacles

    @property
    def n_robots(self) -> int:
        return len(self.robot_starts)

    @property
    def robot_starts_array(self) -> np.ndarray:
        return np.asarray(self.robot_starts, dtype=float).reshape(-1, 2)

    def object_starts(self) -> np.ndarray:
        """(K, 3) start poses of all objects."""
        return np.array([o.start for o in self.objects], dtype=float).reshape(-1, 3)

    def object_goals(self) -> np.ndarray:
        """(K, 3) goal poses of all objects."""
        return np.array([o.goal for o in self.objects], dtype=float).reshape(-1, 3)

    def with_robot_starts(self, starts: np.ndarray) -> Scene:
        return replace(self, robot_starts=tuple((float(x), float(y)) for x, y in starts))

    def to_dict(self) -> dict[str, Any]:
        """The scene-file dict (format ``lamp-scene/1``); ``load_scene`` reads it back."""
        robots: dict[str, Any] = {
            "radius": float(self.robot_radius),
            "starts": [[float(x), float(y)] for x, y in self.robot_starts],
        }
        for key, attr in (("speed", "robot_speed"), ("force_limit", "robot_force_limit")):
            if getattr(self.physics, attr) != getattr(DEFAULT_PHYSICS, attr):
                robots[key] = getattr(self.physics, attr)
        d: dict[str, Any] = {
            "format": "lamp-scene/1",
            "name": self.name,
            "workspace": [float(self.workspace[0]), float(self.workspace[1])],
            "robots": robots,
            "obstacles": [o.to_dict() for o in self.obstacles],
            "objects": [o.to_dict() for o in self.objects],
        }
        if self.physics.to_dict():
            d["physics"] = self.physics.to_dict()
        if self.schedule != "sequential" or self.tasks:  # tasks default to concurrent
            d["schedule"] = self.schedule
        if self.tasks:
            d["tasks"] = [t.to_dict() for t in self.tasks]
        return d
