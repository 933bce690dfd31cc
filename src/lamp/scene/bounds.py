"""A lower bound on any run's makespan, from the scene alone.

Two facts hold for every planner and every schedule: an object moves only while a robot
pushes it, and no robot drives faster than the scene's ``robots.speed`` ``v``. So object
``k`` cannot be placed before

    ``T_k = (reach_k + travel_k) / v``

- ``reach_k``: the nearest robot's drive until it touches the object at its start:
  ``min_i max(0, d(c_i, F_k) - r, g(c_i, p_k) - r - R_k)``, with ``c_i`` robot ``i``'s
  start, ``F_k`` the object's start footprint, ``r`` the robot radius, ``p_k`` the
  object's reference point, ``R_k`` its footprint's farthest point from ``p_k`` and ``g``
  the shortest path round the obstacles themselves, not grown, merged where they meet
  (``lamp.scene.geodesic``).
  The second term holds for footprints that are convex and contain ``p_k`` (circles,
  rectangles, such polygons; others get the first only): a robot whose centre drove ``L``
  to touch the object at ``q`` gives a path round the obstacles from ``c_i`` to ``p_k``
  of ``L + r + |q - p_k|`` (on to ``q`` inside its own disk, on to ``p_k`` inside the
  footprint), so ``g(c_i, p_k) <= L + r + R_k``;
- ``travel_k``: how far its reference point must travel to count as placed: the shortest
  path from its start to its goal around the obstacles and inside the workspace, for a
  disk of the object's inscribed radius about its reference point (``rho_k``: every
  footprint of the object holds that disk, and a placed object never left the
  workspace), less ``SUCCESS_POSITION_TOL``: ``max(0, geo_k - SUCCESS_POSITION_TOL)``
  (``lamp.scene.geodesic``, never longer than the true path). Where the tolerance disk
  round the goal is not clear of the grown obstacles, the straight line stands in for
  ``geo_k`` (a point of the disk may lie beyond an obstacle from the goal).

``makespan_lower_bound(scene) = max_k T_k`` (seconds of simulated time). It ignores the
robots' detours beyond what ``g`` sees, headings, team sizes and that objects share robots, so real
makespans lie above it, by how much says how much time a plan spends on approaches,
turns, repositioning, waiting and sharing. The one assumption beyond the two facts: an
object is not carried along faster than ``v`` (a robot catching up after being blocked,
or an object coasting after a push, could briefly exceed it; the planners never plan
either). ``straight_line=True`` gives the bound with straight-line reach and travel only.

Guarantee (``tests/test_bounds.py``): without obstacles, equals a brute force over robots
and objects; with them, each reach lies between the straight-line one and a robot's drive
to touch the object on a fine grid, and the bound between the straight-line one and the
travel on a fine grid; no recorded run of the test scenes is shorter.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import shapely

from lamp.contract.goals import SUCCESS_POSITION_TOL
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene.geodesic import GrownObstacles
from lamp.scene.model import Circle, Obstacle, Scene, SceneObject, Shape

__all__ = ["MakespanBound", "grown_obstacles", "inscribed_radius", "makespan_lower_bound",
           "object_way", "travel_radius"]


@dataclass(frozen=True)
class MakespanBound:
    """The bound (s), the object that sets it and each object's own ``T_k`` (s)."""

    seconds: float
    critical_object: int
    per_object: tuple[float, ...]


#: Step (m) the inscribed radius is rounded down to before the travel is sought.
RHO_STEP = 0.05


def inscribed_radius(shape: Shape) -> float:
    """The radius of the largest disk centred at ``shape``'s reference point inside it (0
    when the point lies outside; a circle's own radius)."""
    if isinstance(shape, Circle):
        return float(shape.radius)
    foot = to_shapely(shape, (0.0, 0.0, 0.0))
    origin = shapely.Point(0.0, 0.0)
    return float(foot.exterior.distance(origin)) if foot.contains(origin) else 0.0


def _outline(obstacle: Obstacle) -> shapely.Geometry:
    """The obstacle's footprint, a circle as the octagon inscribed in it (inside it, so the
    bound stays valid, with 8 vertices instead of 128)."""
    if isinstance(obstacle.shape, Circle):
        x, y = obstacle.pose[0], obstacle.pose[1]
        return shapely.Point(x, y).buffer(float(obstacle.shape.radius), quad_segs=2)
    return obstacle_geometry(obstacle)


def travel_radius(shape: Shape) -> float:
    """The disk radius an object's travel is sought for: its :func:`inscribed_radius`
    rounded down to a rung of ``RHO_STEP`` (a smaller disk only weakens the bound, and
    objects of similar size share one visibility graph)."""
    return math.floor(inscribed_radius(shape) / RHO_STEP + 1e-9) * RHO_STEP


@lru_cache(maxsize=8)
def grown_obstacles(obstacles: tuple[Obstacle, ...], workspace: tuple[float, float],
                    rho: float, merge: bool = False) -> GrownObstacles:
    """The scene's ``obstacles`` and the outside of its ``workspace`` grown by ``rho``,
    merged where they meet with ``merge`` (``GrownObstacles``; built once per scene,
    radius and ``merge``: callers share it)."""
    return GrownObstacles([_outline(b) for b in obstacles], rho, workspace, merge)


def object_way(scene: Scene, k: int, pose: Sequence[float]) -> np.ndarray | None:
    """The points of the shortest way of object ``k``'s reference point from ``pose`` to
    its goal round the obstacles (the travel of the module docstring, as a path; the
    straight line where that is clear); None when the obstacles separate them."""
    o = scene.objects[k]
    space = grown_obstacles(tuple(scene.obstacles), tuple(scene.workspace),
                            travel_radius(o.shape))
    return space.path(pose, o.goal)


def _star_radius(shape: Shape) -> float | None:
    """``R_k`` of the module docstring: the farthest point of ``shape``'s footprint from
    its reference point, or None when the footprint is not convex with the point inside
    (the reach's geodesic term does not hold for it)."""
    if isinstance(shape, Circle):
        return float(shape.radius)
    foot = to_shapely(shape, (0.0, 0.0, 0.0))
    hull = foot.convex_hull
    if hull.area - foot.area > 1e-9 * max(hull.area, 1.0) or not foot.covers(shapely.Point(0, 0)):
        return None
    return float(np.max(np.hypot(*shapely.get_coordinates(foot).T)))


def _reach(scene: Scene, o: SceneObject, starts: np.ndarray, straight_line: bool) -> float:
    """``reach_k`` of the module docstring for object ``o``, the robots at ``starts``."""
    if isinstance(o.shape, Circle):  # exact (a Shapely circle is an inscribed polygon)
        d = np.hypot(*(starts - np.asarray(o.start[:2])).T) - o.shape.radius
    else:
        d = shapely.distance(shapely.points(starts), to_shapely(o.shape, o.start))
    gap = d - scene.robot_radius
    star = None if straight_line else _star_radius(o.shape)
    if star is None or not scene.obstacles:
        return max(0.0, float(np.min(gap)))
    # merged: the robot's centre keeps its radius from the obstacles (a joint of zero
    # width between two of them, or between one and the border, lets no robot through)
    space = grown_obstacles(tuple(scene.obstacles), tuple(scene.workspace), 0.0, True)

    def longer(i: np.ndarray, below: float = math.inf) -> np.ndarray:  # robots i's terms
        round_ = space.distances(o.start[:2], starts[i], below + scene.robot_radius + star)
        round_ -= scene.robot_radius + star
        return np.maximum(gap[i], np.where(np.isfinite(round_), round_, gap[i]))  # walled off

    first = longer(np.array([int(np.argmin(gap))]))[0]  # only robots nearer can do better
    rest = np.flatnonzero(gap < first)
    return max(0.0, min(first, float(np.min(longer(rest, first))) if len(rest) else first))


def _travel(scene: Scene, o: SceneObject) -> float:
    """``travel_k`` of the module docstring for object ``o``."""
    straight = math.dist(o.goal[:2], o.start[:2])
    space = grown_obstacles(tuple(scene.obstacles), tuple(scene.workspace),
                            travel_radius(o.shape))
    tol_disk = shapely.Point(o.goal[0], o.goal[1]).buffer(SUCCESS_POSITION_TOL)
    if space.blocks(tol_disk):
        return max(0.0, straight - SUCCESS_POSITION_TOL)
    return max(0.0, space.distance(o.start, o.goal) - SUCCESS_POSITION_TOL)


def makespan_lower_bound(scene: Scene, straight_line: bool = False) -> MakespanBound:
    """The lower bound of the module docstring for ``scene``."""
    starts = np.asarray(scene.robot_starts_array, float)
    speed = float(scene.physics.robot_speed)
    per = []
    for o in scene.objects:
        reach = _reach(scene, o, starts, straight_line)
        travel = (max(0.0, math.dist(o.goal[:2], o.start[:2]) - SUCCESS_POSITION_TOL)
                  if straight_line else _travel(scene, o))
        per.append((reach + travel) / speed)
    k = int(np.argmax(per))
    return MakespanBound(float(per[k]), k, tuple(float(t) for t in per))
