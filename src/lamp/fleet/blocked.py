"""A planner that found no plan while other objects move: what it waits for.

Its object waits (``Fleet.plan_failed``) and plans again (:func:`wait_over`) at the
first of:

- an object placed, or failed after it started (``Fleet.finished``);
- an object that stood in the space it needs when its planner failed gone from that space:
  its body and the robots of its sub-team all out of it (the space is
  :func:`blocked_space`: its way, its robots' approach, its last plan's claim);
- ``BLOCKED_WAKE_EVENTS`` events, whatever blocked it (a robot of nobody's team, the
  obstacles, a body that stays).

Whether a noted object left is looked at once per event, not at every step of the others
(a failed search is costly), and the objects' poses are read only then and once at each
failure (under sensing noise each read is a draw of the sensor's: a run stays
deterministic, but a body on the space's edge may read as gone). Tested in
``tests/test_fleet_blocked.py``. These are the rules; ``Fleet`` applies them.
"""

from __future__ import annotations

import numpy as np
import shapely

from lamp.fleet.state import ObjectState
from lamp.fleet.teams import needed_space
from lamp.scene.model import Scene

__all__ = ["BLOCKED_WAKE_EVENTS", "blocked_space", "looks_now", "wait_over"]

#: A planner that found no plan while others moved plans again after this many events
#: (segments ending) at the latest (module docstring).
BLOCKED_WAKE_EVENTS = 6


def blocked_space(scene: Scene, o: ObjectState, poses: np.ndarray,
                  robot_positions: np.ndarray) -> shapely.Geometry:
    """The space ``o`` needs (``teams.needed_space``: to its detour's end if it has one,
    else its goal) with the objects at ``poses`` and its robots at ``robot_positions``:
    the objects standing in it when its planner failed are what it waits on."""
    obj = scene.objects[o.index]
    goal = obj.goal if o.detour is None else o.detour
    team = np.asarray(robot_positions, float)[o.team, :2]
    return needed_space(obj.shape, poses[o.index], goal, team, scene.robot_radius, o.claim)


def looks_now(o: ObjectState, now: int) -> bool:
    """Whether ``o`` looks at event ``now`` whether a noted object left its space: it has
    noted some and has not looked at this event yet (once per event)."""
    return bool(o.blockers) and now > o.looked_at


def wait_over(o: ObjectState, finished: int, now: int, left: bool) -> bool:
    """Whether the wait of ``o`` (its planner found no plan) is over at event ``now`` with
    ``finished`` objects done: one more was done since, ``BLOCKED_WAKE_EVENTS`` events
    passed, or a noted object ``left`` its space."""
    assert o.blocked_at is not None
    done_then, events_then = o.blocked_at
    return finished > done_then or now - events_then >= BLOCKED_WAKE_EVENTS or left
