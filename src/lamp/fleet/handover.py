"""Hand-over: free robots near a moving object take the places of its team's far robots.

A sub-team is made of the robots free when its object starts (``teams.allocate``). On a
large map those can stand across the map, robots freed by an object placed 40 m away,
while seconds later another team is freed right beside the object: on ``fleet-16``
(seed 1) object 3's team of two drove 40 m for 218 s of simulated time while the three
robots freed 5 s after it started stood 4 m from it, idle.

So between a team's segments, each of its robots standing farther than
``TRANSIT_RADIUS`` from its object (it would transit) may give its place to a free
robot whose route to the object's staging area is at least ``HANDOVER_GAIN`` shorter
(routes as transit drives them, ``transit.routes``). The team's loop ends
(``team_changed``), the object plans anew with its new team, and the far robot is free
where it stands. Teams larger than the model's budget (a blocked planner's, which took
the free robots near its way) are left alone.

:func:`swaps` chooses the pairs: as many as possible, from the free robots nearest by
route (tested against a brute force).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from lamp.contract.model import MAX_ROBOTS
from lamp.fleet.objects import sub_scene
from lamp.fleet.teams import planar_distance
from lamp.fleet.transit import TRANSIT_RADIUS, routes
from lamp.scene.model import Scene

__all__ = ["HANDOVER_GAIN", "better_team", "swaps"]

#: How much shorter (m) a free robot's route to the object must be than a team robot's
#: for it to take that robot's place: a hand-over costs the loop its plan, so it must
#: save at least a transit radius of driving.
HANDOVER_GAIN = TRANSIT_RADIUS


def swaps(team_routes: Sequence[float], free_routes: Sequence[float],
          gain: float = HANDOVER_GAIN) -> list[tuple[int, int]]:
    """Pairs ``(t, f)``: team robot ``t`` (an index into ``team_routes``) gives its place
    to free robot ``f`` (into ``free_routes``); route lengths in metres, ``inf`` for none.

    Guarantees: every pair has ``free_routes[f] + gain <= team_routes[t]`` with a finite
    free route; each robot is in at most one pair; the number of pairs is the largest
    possible; and the free robots taken are the nearest ones (ties by index).
    Deterministic. Greedy: the valid free robots of a team robot are a prefix of the
    free robots sorted by route, nested by team route, so pairing the team robots from
    the nearest up with the nearest free robots left is a largest matching."""
    free = sorted((d, f) for f, d in enumerate(free_routes) if math.isfinite(d))
    team = sorted((d, t) for t, d in enumerate(team_routes))
    pairs: list[tuple[int, int]] = []
    j = 0
    for d_t, t in team:
        if j < len(free) and free[j][0] + gain <= d_t:
            pairs.append((t, free[j][1]))
            j += 1
    return pairs


def better_team(scene: Scene, k: int, team: Sequence[int], free: Sequence[int],
                robot_positions: np.ndarray, pose: np.ndarray,
                observe: Callable[[], np.ndarray]) -> list[int] | None:
    """Object ``k``'s team with its far robots handed over to nearer ``free`` ones
    (module docstring; ascending), or None when nothing changes. ``pose`` is the object's
    pose as its loop last saw it; ``observe()`` reads every object's pose, and is called
    (as the routes are computed) only when a team robot stands farther than
    ``TRANSIT_RADIUS`` from ``pose``: under sensing noise a reading is a draw of the
    sensor's, so a check that finds nothing draws none."""
    if not free or len(team) > MAX_ROBOTS:
        return None
    pos = np.asarray(robot_positions, float)
    far = [i for i in team if planar_distance(pos[i], pose) > TRANSIT_RADIUS]
    if not far:
        return None
    field = routes(sub_scene(scene, [*team, *free], pos), k, observe())
    pairs = swaps([field.length(pos[i]) for i in far], [field.length(pos[i]) for i in free])
    if not pairs:
        return None
    out = set(team) - {far[t] for t, _ in pairs}
    return sorted(out | {free[f] for _, f in pairs})
