"""Who pushes what: robots split into sub-teams, one per moving object.

:func:`allocate` shares the free robots equally among the objects ready to move (in
priority order, each the robots nearest to it): at most ``MAX_ROBOTS`` each (the model's
budget: more would stand idle), at least ``MIN_TEAM``; a lone robot only when no other
object is moving (no robot will be freed); robots left over when the next object cannot
start join the started teams. More objects moving at once, each with fewer robots, places
them sooner: on IROS with 9 robots (``benchmarks/fleet_iros9.py``), teams of 2 and 3 (4
objects at once) placed all 9 objects in 191 s, 3 teams of 3 in 249 s. A team keeps its
robots until its object is placed or given up; then they are free for the next object.
Robots no object needs stand still where they are (every plan sees them as obstacles).
Which ready objects go first is :func:`least_conflict_order`: those whose way crosses the
fewest ways of the objects moving (IROS with 9 robots: 191 s -> 164 s).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import shapely

from lamp.contract.model import MAX_ROBOTS
from lamp.geometry.shapes import to_shapely
from lamp.scene.model import Shape

__all__ = ["MIN_TEAM", "allocate", "corridor", "least_conflict_order", "nearest"]

#: The smallest sub-team an object starts with while other objects are moving.
MIN_TEAM = 2


def nearest(pool: Sequence[int], robot_positions: np.ndarray, centre: np.ndarray,
            n: int) -> list[int]:
    """The ``n`` robots of ``pool`` nearest to ``centre`` (ties by index), nearest first."""
    c = np.asarray(centre, float)[:2]
    d = [float(np.hypot(*(np.asarray(robot_positions[i], float) - c))) for i in pool]
    return [pool[j] for j in sorted(range(len(pool)), key=lambda j: (d[j], pool[j]))[:n]]


def allocate(ready: Sequence[int], free: Sequence[int], robot_positions: np.ndarray,
             object_poses: np.ndarray, others_moving: bool) -> dict[int, list[int]]:
    """Sub-teams for the ``ready`` objects (priority order) from the ``free`` robots.

    The free robots are shared equally among the ready objects: each gets ``share`` =
    ``len(free) // len(ready)`` of the free robots nearest to its centre (ties by index),
    at least ``MIN_TEAM`` and at most ``MAX_ROBOTS``; an object that would get fewer than
    ``MIN_TEAM`` (1 when nothing else moves and it is the first) waits, and so do those
    after it. Robots left over when no further object can start join the teams, each the
    team of the nearest object among those below ``MAX_ROBOTS`` (ties by priority).
    Deterministic; returns object -> robots (ascending)."""
    pool = list(free)
    teams: dict[int, list[int]] = {}
    if not ready:
        return teams
    share = max(MIN_TEAM, min(MAX_ROBOTS, len(pool) // len(ready)))
    moving = others_moving
    for k in ready:
        need = min(share, len(pool))
        if need < (MIN_TEAM if moving else 1):
            break
        chosen = nearest(pool, robot_positions, object_poses[k], need)
        teams[k] = sorted(chosen)
        pool = [i for i in pool if i not in chosen]
        moving = True
    if len(teams) < len(ready):  # the next object cannot start: help the started ones
        for i in list(pool):
            open_ = [k for k in teams if len(teams[k]) < MAX_ROBOTS]
            if not open_:
                break
            p = np.asarray(robot_positions[i], float)
            k = min(open_, key=lambda k: (float(np.hypot(*(np.asarray(object_poses[k][:2],
                                                                    float) - p))),
                                          list(teams).index(k)))
            teams[k] = sorted(teams[k] + [i])
    return teams


def least_conflict_order(candidates: Sequence[int], corridors: Mapping[int, shapely.Geometry],
                         busy: Sequence[shapely.Geometry]) -> list[int]:
    """``candidates`` in the order they should start: greedily, next the one whose
    corridor (``corridors[k]``: the way it has to go) meets the fewest of ``busy`` (the
    moving objects' corridors) and of the corridors of those put before it; ties by
    index. Objects whose ways do not cross start together, and crossing ones wait."""
    rest, taken, out = sorted(candidates), list(busy), []
    while rest:
        k = min(rest, key=lambda k: (sum(corridors[k].intersects(b) for b in taken), k))
        rest.remove(k)
        out.append(k)
        taken.append(corridors[k])
    return out


def corridor(shape: Shape, pose: np.ndarray, goal: np.ndarray, robot_radius: float
             ) -> shapely.Geometry:
    """An object's way from ``pose`` to ``goal``: the convex hull of its footprints at
    both, grown by a robot diameter."""
    ends = shapely.union_all([to_shapely(shape, np.asarray(pose, float)),
                              to_shapely(shape, np.asarray(goal, float))])
    return ends.convex_hull.buffer(2 * float(robot_radius))
