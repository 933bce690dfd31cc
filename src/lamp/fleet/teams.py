"""Who pushes what: robots split into sub-teams, one per moving object.

:func:`allocate` gives each object that is ready to move (in priority order) the
``MAX_ROBOTS`` free robots nearest to it (the model's budget: more would stand idle), or,
when fewer are free, at least ``MIN_TEAM``; a lone robot only when no other object is
moving (no robot will be freed). A team keeps its robots until its object is placed or
given up; then they are free for the next object. Robots no object needs stand still
where they are (every plan sees them as obstacles).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from lamp.contract.model import MAX_ROBOTS

__all__ = ["MIN_TEAM", "allocate", "nearest"]

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
    """Sub-teams for the ``ready`` objects (priority order) from the ``free`` robots: each
    gets up to ``MAX_ROBOTS`` of the free robots nearest to its centre (ties by index);
    an object that would get fewer than ``MIN_TEAM`` (1 when nothing else moves and it is
    the first) waits, and so do those after it. Deterministic; returns object -> robots
    (ascending)."""
    pool = list(free)
    teams: dict[int, list[int]] = {}
    moving = others_moving
    for k in ready:
        need = MAX_ROBOTS if len(pool) >= MAX_ROBOTS else len(pool)
        if need < (MIN_TEAM if moving else 1):
            break
        chosen = nearest(pool, robot_positions, object_poses[k], need)
        teams[k] = sorted(chosen)
        pool = [i for i in pool if i not in chosen]
        moving = True
    return teams
