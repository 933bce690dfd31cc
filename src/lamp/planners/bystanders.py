"""Bystanders: robots that take no part in a motion and stand far from it.

A team's robot that no contact needs and that already stands clear of the push keeps its
place (its waiting spot is where it stands). When it also stands far from everything the
motion involves, routing it is pure cost: the robot-space window, the multi-robot
planner's lattice and its distance fields all span the strip between it and the object.
One far robot of a fleet's sub-team (drawn from robots across a 50 m map) made every
Verify call of its object route over such a strip: 2 s per verified motion instead of
0.03 s.

:func:`bystanders` finds them. Guarantee: a robot it returns is more than
``2 * robot_radius + BYSTANDER_GAP`` outside (in both axes' sense: outside the window grown
by that pad) the window that ``window_of`` gives for the movers' positions, so no robot
whose centre stays inside that window, as the robots of a plan made in the window's robot
space do, can touch it while it holds still. The set is closed: growing the window by any
robot left out would not reach another robot.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["BYSTANDER_GAP", "bystanders", "route_movers", "standing_on_goal"]

#: Clearance (m) beyond robot contact between a bystander and the movers' window.
BYSTANDER_GAP = 0.05

Window = tuple[float, float, float, float]


def _near(window: Window, points: np.ndarray, pad: float) -> np.ndarray:
    """Which ``points`` lie inside ``window`` grown by ``pad`` on every side."""
    x0, y0, x1, y1 = window
    return ((points[:, 0] > x0 - pad) & (points[:, 0] < x1 + pad)
            & (points[:, 1] > y0 - pad) & (points[:, 1] < y1 + pad))


def bystanders(window_of: Callable[[np.ndarray], Window], positions: np.ndarray,
               movers: np.ndarray, candidates: np.ndarray, pad: float) -> np.ndarray:
    """Mask of the ``candidates`` (mask) that may hold still outside the window.

    ``movers`` (mask) move in any case; ``window_of(points)`` is the window the motion
    needs for the movers at ``points``. A candidate within ``pad`` of the window becomes
    a mover (the window then grows with it) until no other candidate is that near.
    """
    pos = np.asarray(positions, float).reshape(-1, 2)
    moving = np.asarray(movers, bool) | ~np.asarray(candidates, bool)
    while True:
        grown = moving | _near(window_of(pos[moving]), pos, pad)
        if np.array_equal(grown, moving):
            return ~moving
        moving = grown


def standing_on_goal(positions: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """(N,) per robot the index of a goal exactly where it stands (each goal given to one
    robot at most, lowest indices first), -1 for none."""
    pos = np.asarray(positions, float).reshape(-1, 2)
    out = np.full(len(pos), -1, np.int64)
    taken: set[int] = set()
    for i, p in enumerate(pos):
        for j in np.flatnonzero(np.all(np.asarray(goals, float) == p, axis=1)).tolist():
            if j not in taken:
                out[i] = j
                taken.add(j)
                break
    return out


def route_movers(route: Callable[..., Any], q_object: np.ndarray, starts: np.ndarray,
                 goals: np.ndarray, own_goal: np.ndarray, held: np.ndarray, space: Any,
                 time_limit: float) -> Any:
    """``route`` (a ``MultiRobotPlanner``) for the robots not ``held`` to the goals not
    held; each held robot's rows repeat where it stands and ``goal_of`` gives it its own
    goal ``own_goal[i]``. Without held robots, ``route``'s answer unchanged."""
    held = np.asarray(held, bool)
    if not held.any():
        return route(q_object, starts, goals, space, time_limit)
    kept = np.ones(len(goals), bool)
    kept[own_goal[held]] = False
    goal_ids = np.flatnonzero(kept)
    plan = route(q_object, starts[~held], goals[kept], space, time_limit)
    paths = np.repeat(starts[:, None, :], plan.paths.shape[1], axis=1)
    paths[~held] = plan.paths
    goal_of = own_goal.copy()
    sub = np.asarray(plan.goal_of)
    goal_of[~held] = np.where(sub >= 0, goal_ids[np.maximum(sub, 0)], -1)
    out = copy.copy(plan)
    out.paths, out.goal_of = paths, goal_of
    return out
