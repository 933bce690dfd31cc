"""Geometric primitives: poses, the three shape kinds and static obstacles.

Conventions, stated once for the whole package:
- units are metres and radians; the workspace is the rectangle [0, W] x [0, H];
- a pose is ``(x, y, theta)`` with theta counter-clockwise from +x;
- shapes are described in their own frame, centred on its origin; an ``Obstacle`` places
  one in the world (circles and rectangles by centre and angle, polygons by world-frame
  points with the identity pose).

All classes are frozen dataclasses; validation of user input happens in
``lamp.scene.loader`` so that these types stay cheap to construct in hot code. This module
depends on NumPy alone, so that every other geometry module can use it without loading the
scene format's dependencies.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Union

import numpy as np

__all__ = ["Circle", "Obstacle", "Point", "Polygon", "Pose", "Rectangle", "Shape",
           "shape_from_dict"]

Pose = tuple[float, float, float]
Point = tuple[float, float]


@dataclass(frozen=True)
class Circle:
    """A disk of ``radius`` centred on the frame origin."""

    radius: float

    def to_dict(self) -> dict[str, Any]:
        return {"type": "circle", "radius": float(self.radius)}

    @property
    def bounding_radius(self) -> float:
        return float(self.radius)


@dataclass(frozen=True)
class Rectangle:
    """An axis-aligned (in its own frame) rectangle of extent ``size = (sx, sy)``."""

    size: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return {"type": "rectangle", "size": [float(self.size[0]), float(self.size[1])]}

    @property
    def bounding_radius(self) -> float:
        return 0.5 * float(np.hypot(*self.size))


@dataclass(frozen=True)
class Polygon:
    """A simple polygon given by its vertices in its own frame (either orientation)."""

    points: tuple[Point, ...]

    def to_dict(self) -> dict[str, Any]:
        return {"type": "polygon", "points": [[float(x), float(y)] for x, y in self.points]}

    @property
    def bounding_radius(self) -> float:
        pts = np.asarray(self.points, dtype=float)
        return float(np.max(np.hypot(pts[:, 0], pts[:, 1])))


Shape = Union[Circle, Rectangle, Polygon]  # noqa: UP007 (a runtime alias, 3.10-safe)


def shape_from_dict(d: dict[str, Any]) -> Shape:
    """Build a shape from its dict form (``{"type": "circle", "radius": r}`` and so on).

    This is the trusted, unvalidated path used by the API (e.g. ``Model.propose``); files
    go through ``lamp.scene.loader`` which reports errors with file and field names.
    """
    kind = d.get("type")
    if kind == "circle":
        return Circle(float(d["radius"]))
    if kind == "rectangle":
        sx, sy = d["size"]
        return Rectangle((float(sx), float(sy)))
    if kind == "polygon":
        return Polygon(tuple((float(x), float(y)) for x, y in d["points"]))
    raise ValueError(f"unknown shape type {kind!r}; expected circle, rectangle or polygon")


@dataclass(frozen=True)
class Obstacle:
    """A static obstacle: ``shape`` placed at world ``pose``.

    World-frame polygons from files are stored with ``pose == (0, 0, 0)``.
    """

    shape: Shape
    pose: Pose = (0.0, 0.0, 0.0)

    def to_dict(self) -> dict[str, Any]:
        x, y, th = (float(v) for v in self.pose)
        if isinstance(self.shape, Circle):
            return {"type": "circle", "center": [x, y], "radius": float(self.shape.radius)}
        if isinstance(self.shape, Rectangle):
            return {
                "type": "rectangle",
                "center": [x, y],
                "size": [float(self.shape.size[0]), float(self.shape.size[1])],
                "angle": th,
            }
        c, s = np.cos(th), np.sin(th)
        pts = [[x + c * px - s * py, y + s * px + c * py] for px, py in self.shape.points]
        return {"type": "polygon", "points": [[float(a), float(b)] for a, b in pts]}
