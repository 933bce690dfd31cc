"""A planner that found no plan while other objects move: what it waits for.

Its object waits (``Fleet.plan_failed``) and plans again (:func:`wait_over`) at the
first of:

- when unplaced objects stood in the space it needs when its planner failed (the space is
  :func:`blocked_space`: its way, its robots' approach, its last plan's claim): one of
  them gone from that space (its body and the robots of its sub-team all out of it) or
  placed there (it stands for good: the planner must go round it);
- when none did: an object placed, or failed after it started (``Fleet.finished``);
- :func:`patience` events, whatever blocked it (a robot of nobody's team, the obstacles,
  a body that stays): ``BLOCKED_WAKE_EVENTS`` for each other object moving then, so that
  a planner waits about as many of the others' segments in a fleet of 40 as of 2 (each
  retry is a full search, and counts against its object's budgets).

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

__all__ = ["BLOCKED_WAKE_EVENTS", "blocked_space", "looks_now", "patience", "wait_over"]

#: A planner that found no plan while others moved plans again after this many events
#: (segments ending) for each other object moving then, at the latest (module docstring).
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


def patience(others_moving: int) -> int:
    """The events after which a planner that found no plan while ``others_moving`` other
    objects moved plans again at the latest: ``BLOCKED_WAKE_EVENTS`` for each (one at
    least)."""
    return BLOCKED_WAKE_EVENTS * max(1, others_moving)


def wait_over(o: ObjectState, finished: int, now: int, left: bool) -> bool:
    """Whether the wait of ``o`` (its planner found no plan) is over at event ``now`` with
    ``finished`` objects done: a noted object ``left`` its space (or was placed), or, with
    none noted, one more object was done since; or :func:`patience` events passed."""
    assert o.blocked_at is not None
    done_then, events_then = o.blocked_at
    woken = left if o.blockers else finished > done_then
    return woken or now - events_then >= patience(o.others_moving)
