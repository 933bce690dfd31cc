"""Making way: an object standing in a blocked object's way moves aside first.

Objects whose goals are each other's places (two loads swapping places, three rotating
round), or that stand in each other's way in a dead end, block one another for good: each
planner finds no plan while the other stands where it must pass, and waiting changes
nothing. When the fleet schedule is stuck (nothing runs and the planners wait for a
change, ``Fleet._unstick``), :func:`make_way` looks, in priority order, for a blocked
object ``k`` in whose way another blocked object ``j`` stands: its footprint within
``k``'s bounding radius and a robot diameter of ``k``'s route round the map's obstacles
to its goal (:func:`way_of`, :func:`standing_in_way`; the first such along the route).
``j`` is blocked too, or stands without robots (waiting for robots, or to start: with few
robots, one team at a time). ``j`` then gets a *detour*: a pose to move to first
(:func:`buffer_pose`), which its loop plans to and runs like a goal (LAMP's own loop and
Verify; ``lamp.fleet.objects``; it stops there at any heading, the clearance being
measured by the bounding radius); when it stands there, or finds no way there, the detour
ends (``Fleet.detour_done``), the blocked planners plan again and ``j`` goes on to its own
goal. A ``j`` without robots gets ``k``'s (``k`` waits for robots), and a detour only if
its own way is shut too or it may not start yet (``Fleet.may_start``: its goal would cut
the way of ``k`` or of another object not yet done, ``fleet.precedence``); else it goes
straight to its goal. Each (``j``, ``k``) pair
makes way at most once, so the schedule still ends. Runs that never get stuck are
unchanged (the ``fleet`` family: all 25 the same).

The buffer is the free position nearest ``j`` (at its heading, on a grid of
``BUFFER_STEP``) whose distance to anything ``j`` must keep clear of is at least ``j``'s
bounding radius and a robot diameter (room for robots all round): the obstacles and the
workspace border, the other objects and robots where they stand, the other unplaced
objects at their goals, and the band ``k`` sweeps along its route; which ``j`` can reach
(``landmark.route_length`` round the obstacles and the objects); and from which ``j``
can reach its own goal round the obstacles and ``k`` placed (not a pocket ``k`` will
close: a corridor swap once put the buffer beyond ``k``'s goal in the corridor). The search widens
from ``BUFFER_REACH`` metres around ``j`` to the whole map, doubling; at each width the
routes of the ``_REACH_CHECKS`` nearest clear positions not yet tried are sought, so the
buffer is the nearest clear reachable position unless more clear positions nearer than it
are walled off.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence, Set
from dataclasses import dataclass, field, replace

import numpy as np
import shapely

from lamp.fleet.state import ObjectState, ObjectStatus
from lamp.fleet.teams import in_way_of
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.primitives import Obstacle
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene.model import Scene
from lamp.search.landmark import route_length, route_path

__all__ = ["BUFFER_REACH", "BUFFER_STEP", "MakeWay", "Move", "buffer_pose", "make_way",
           "route_of", "stands_still", "standing_in_way", "way_of", "with_goal"]

#: Grid (m) on which buffer positions are sought.
BUFFER_STEP = 0.1
#: First search radius (m) around the object; doubled until the map is covered.
BUFFER_REACH = 3.0
#: Buffer candidates checked for reachability (nearest first) per search radius.
_REACH_CHECKS = 8


def route_of(scene: Scene, k: int, pose: np.ndarray, step: float = BUFFER_STEP
             ) -> np.ndarray | None:
    """Object ``k``'s route from ``pose`` to its goal round the map's obstacles
    (``landmark.route_path``; the other objects move, so they do not count); None when
    none joins them."""
    obj = scene.objects[k]
    space = ObjectSpace(obj.shape, scene.workspace, scene.obstacles, static=scene.fixed_obstacles)
    return route_path(space, (float(pose[0]), float(pose[1])),
                      (float(obj.goal[0]), float(obj.goal[1])), step)


def way_of(scene: Scene, k: int, pose: np.ndarray, step: float = BUFFER_STEP
           ) -> shapely.LineString:
    """Object ``k``'s way from ``pose`` to its goal: its route (:func:`route_of`), or the
    straight line when no route joins them."""
    path = route_of(scene, k, pose, step)
    if path is None:
        path = np.array([np.asarray(pose, float)[:2], np.asarray(scene.objects[k].goal, float)[:2]])
    return shapely.LineString(path)


def standing_in_way(scene: Scene, k: int, way: shapely.LineString, poses: np.ndarray,
                    candidates: list[int]) -> int | None:
    """The first along ``way`` (object ``k``'s, :func:`way_of`) of ``candidates`` (objects,
    at ``poses``) that stand in it (``teams.in_way_of``: their footprint comes within
    ``k``'s circumscribed radius plus a robot diameter of it); None if none does."""
    hits = in_way_of(scene, poses, k, [j for j in candidates if j != k], way)
    return min(hits, key=lambda j: (way.project(shapely.Point(poses[j][:2])), j), default=None)


def buffer_pose(scene: Scene, j: int, poses: np.ndarray, robot_positions: np.ndarray,
                team: list[int], keep: list[shapely.Geometry],
                then: Sequence[Obstacle] = (), step: float = BUFFER_STEP
                ) -> np.ndarray | None:
    """The pose (``j``'s heading) ``j`` moves aside to (module docstring): clear by ``j``'s
    bounding radius and a robot diameter of the obstacles, the border, the other objects
    at ``poses``, the robots not in ``team`` and ``keep``; reachable now (round the
    obstacles and the other objects); ``j``'s goal reachable from it round the obstacles
    and ``then`` (what will stand when ``j`` goes on: the object it made way for, placed);
    nearest ``j`` (ties by grid order). None when no position qualifies."""
    obj = scene.objects[j]
    pose = np.asarray(poses[j], float)
    r = float(scene.robot_radius)
    clear = float(obj.shape.bounding_radius) + 2.0 * r
    W, H = scene.workspace
    parts = [obstacle_geometry(o) for o in scene.obstacles] + list(keep)
    parts += [to_shapely(o.shape, poses[i]) for i, o in enumerate(scene.objects) if i != j]
    parts += [shapely.Point(*p).buffer(r) for i, p in enumerate(np.asarray(robot_positions))
              if i not in team]
    blocked = shapely.union_all(parts) if parts else shapely.GeometryCollection()
    shapely.prepare(blocked)
    xs = np.arange(clear, W - clear + 1e-9, step)
    ys = np.arange(clear, H - clear + 1e-9, step)
    if len(xs) == 0 or len(ys) == 0:
        return None
    space = ObjectSpace.from_scene(scene, j, poses)
    onward = ObjectSpace(obj.shape, scene.workspace, (*scene.obstacles, *then),
                         static=scene.fixed_obstacles)
    goal = (float(obj.goal[0]), float(obj.goal[1]))
    checked: set[tuple[int, int]] = set()  # positions whose route was sought
    reach = BUFFER_REACH
    while True:
        ix = np.flatnonzero(np.abs(xs - pose[0]) <= reach)
        iy = np.flatnonzero(np.abs(ys - pose[1]) <= reach)
        gi, gj = (a.ravel() for a in np.meshgrid(ix, iy, indexing="ij"))
        ok = ~np.asarray(shapely.dwithin(blocked, shapely.points(xs[gi], ys[gj]), clear), bool)
        gi, gj = gi[ok], gj[ok]
        d = np.hypot(xs[gi] - pose[0], ys[gj] - pose[1])
        fresh = [c for c in np.lexsort((gj, gi, d)).tolist()
                 if (gi[c], gj[c]) not in checked][:_REACH_CHECKS]
        for c in fresh:
            checked.add((gi[c], gj[c]))
            x, y = float(xs[gi[c]]), float(ys[gj[c]])
            if (route_length(space, (pose[0], pose[1]), (x, y), step) is not None
                    and route_length(onward, (x, y), goal, step) is not None):
                return np.array([x, y, pose[2]])
        if reach >= math.hypot(W, H):
            return None
        reach *= 2.0


def with_goal(scene: Scene, k: int, goal: np.ndarray) -> Scene:
    """``scene`` with object ``k``'s goal moved to ``goal``."""
    objs = list(scene.objects)
    objs[k] = replace(objs[k], goal=tuple(float(v) for v in goal))
    return replace(scene, objects=tuple(objs))


def stands_still(o: ObjectState, objects: Sequence[ObjectState],
                 after: Callable[[int], Sequence[int]]) -> bool:
    """Whether ``o`` stays where it stands until something is done for it: its planner
    waits for a change (with robots), or it waits for robots, or to start (the objects
    its current task waits for, ``after(k)``: ``Board.after``, placed); and it is on no
    detour."""
    if o.detour is not None:
        return False
    if o.status == ObjectStatus.ACTIVE:
        return (o.blocked_at is not None and bool(o.team)) or o.needs_team
    return o.status == ObjectStatus.WAITING and all(
        objects[a].status == ObjectStatus.PLACED for a in after(o.index))


@dataclass(frozen=True)
class Move:
    """Object ``j`` makes way for the blocked object ``k``: it moves to ``target`` first
    (None: straight to its goal) with ``team``, its own robots or, when it has none,
    ``k``'s (``k`` then waits for robots)."""

    j: int
    k: int
    target: np.ndarray | None
    team: list[int]


@dataclass
class MakeWay:
    """What :func:`make_way` decided: the pairs it tried (each tried once, ``Fleet``
    remembers them), its notes for the log ((what, object, detail)) and the move, if
    any."""

    tried: list[tuple[int, int]] = field(default_factory=list)
    notes: list[tuple[str, int, str]] = field(default_factory=list)
    move: Move | None = None


def make_way(scene: Scene, objects: Sequence[ObjectState], blocked: Sequence[ObjectState],
             poses: np.ndarray, robot_positions: np.ndarray, tried: Set[tuple[int, int]],
             may_start: Callable[[int], bool], after: Callable[[int], Sequence[int]]
             ) -> MakeWay:
    """For the first of ``blocked`` (priority order) in whose way an object stands still
    (module docstring; pairs in ``tried`` are not tried again): that object moves aside,
    or, without robots and with its own way clear, gets the blocked one's robots and goes
    to its goal (``may_start``: whether an object may start now; ``after``: the objects
    each object's current task waits for, ``Board.after``). Objects at ``poses``,
    robots at ``robot_positions``; the decision is ``Fleet``'s to apply."""
    out = MakeWay()
    poses = np.asarray(poses, float)
    still = [p.index for p in objects if stands_still(p, objects, after)]
    unplaced = [p.index for p in objects if p.unplaced]
    for o in blocked:
        k = o.index
        way = way_of(scene, k, poses[k])
        j = standing_in_way(scene, k, way, poses, [i for i in still if i != k and (i, k)
                                                   not in tried and (i, k) not in out.tried])
        if j is None or not o.team:
            continue
        out.tried.append((j, k))
        J = objects[j]
        team = J.team or list(o.team)
        target = None
        shut = standing_in_way(scene, j, way_of(scene, j, poses[j]), poses,
                               [i for i in unplaced if i != j]) is not None
        if J.team or shut or not may_start(j):
            keep = [way.buffer(float(scene.objects[k].shape.bounding_radius))]
            keep += [to_shapely(scene.objects[i].shape, np.asarray(scene.objects[i].goal, float))
                     .buffer(2 * scene.robot_radius) for i in unplaced if i != j]
            placed = Obstacle(scene.objects[k].shape, scene.objects[k].goal)
            target = buffer_pose(scene, j, poses, robot_positions, team, keep, (placed,))
            out.notes.append(("make_way", j, f"for {k}: "
                              f"{None if target is None else np.round(target, 2).tolist()}"))
            if target is None:
                continue
        out.move = Move(j, k, target, list(team))
        return out
    return out
