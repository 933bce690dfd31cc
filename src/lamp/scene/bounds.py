"""A lower bound on any run's makespan, from the scene alone.

Two facts hold for every planner and every schedule: an object moves only while a robot
pushes it, and no robot drives faster than the scene's ``robots.speed`` ``v``. So object
``k`` cannot be placed before

    ``T_k = (reach_k + travel_k) / v``

- ``reach_k``: the nearest robot's straight-line drive until it touches the object at its
  start: ``min_i max(0, d(c_i, F_k) - r)``, with ``c_i`` robot ``i``'s start, ``F_k`` the
  object's start footprint and ``r`` the robot radius;
- ``travel_k``: the straight-line distance its reference point must cover to count as
  placed: ``max(0, |p_goal - p_start| - SUCCESS_POSITION_TOL)``.

``makespan_lower_bound(scene) = max_k T_k`` (seconds of simulated time). It ignores
obstacles, headings, team sizes and that objects share robots, so real makespans lie
above it, by how much says how much time a plan spends on detours, turns, waiting and
sharing. The one assumption beyond the two facts: an object is not carried along faster
than ``v`` (a robot catching up after being blocked, or an object coasting after a push,
could briefly exceed it; the planners never plan either).

Guarantee (``tests/test_bounds.py``): equals a brute force over robots and objects, and no
recorded run of the test scenes is shorter.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from lamp.contract.goals import SUCCESS_POSITION_TOL
from lamp.geometry.shapes import to_shapely
from lamp.scene.model import Circle, Scene

__all__ = ["MakespanBound", "makespan_lower_bound"]


@dataclass(frozen=True)
class MakespanBound:
    """The bound (s), the object that sets it and each object's own ``T_k`` (s)."""

    seconds: float
    critical_object: int
    per_object: tuple[float, ...]


def makespan_lower_bound(scene: Scene) -> MakespanBound:
    """The lower bound of the module docstring for ``scene``."""
    starts = np.asarray(scene.robot_starts_array, float)
    robots = shapely.points(starts)
    speed = float(scene.physics.robot_speed)
    per = []
    for o in scene.objects:
        if isinstance(o.shape, Circle):  # exact (a Shapely circle is an inscribed polygon)
            d = np.hypot(*(starts - np.asarray(o.start[:2])).T) - o.shape.radius
        else:
            d = shapely.distance(robots, to_shapely(o.shape, o.start))
        gap = d - scene.robot_radius
        reach = max(0.0, float(np.min(gap)))
        travel = max(0.0, math.dist(o.goal[:2], o.start[:2]) - SUCCESS_POSITION_TOL)
        per.append((reach + travel) / speed)
    k = int(np.argmax(per))
    return MakespanBound(float(per[k]), k, tuple(float(t) for t in per))
