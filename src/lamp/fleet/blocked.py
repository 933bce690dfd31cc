"""A planner that found no plan while other objects move: what it waits for.

Its object waits (``Fleet.plan_failed``) and plans again (:func:`wake_blocked`) at the
first of:

- an object placed, or failed after it started (``Fleet.finished``);
- an object that stood in the space it needs when its planner failed gone from that space:
  its body and the robots of its sub-team all out of it (:func:`note_blocked` notes them;
  the space is ``teams.needed_space``: its way, its robots' approach, its last plan's
  claim). On IROS with 9 robots, seed 0, the robots that had just placed object 5 stood
  at object 6's goal; they left within seconds, and object 6 now plans again then, not
  six events later (``docs/fleet.md``);
- ``BLOCKED_WAKE_EVENTS`` events, whatever blocked it (a robot of nobody's team, the
  obstacles, a body that stays).

Whether a noted object left is looked at once per event, not at every step of the others
(a failed search is costly), and the objects' poses are read only then and once at each
failure (under sensing noise each read is a draw of the sensor's: a run stays
deterministic, but a body on the space's edge may read as gone). Every noted object
leaving may wake the planner once; measured, it changed no count of failed plans on the
``fleet`` family or under ``noise-high`` (``docs/fleet.md``). Tested in
``tests/test_fleet_blocked.py``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from lamp.fleet.teams import needed_space

if TYPE_CHECKING:
    from lamp.fleet.coordinator import Fleet
    from lamp.fleet.state import ObjectState

__all__ = ["BLOCKED_WAKE_EVENTS", "note_blocked", "wake_blocked"]

#: A planner that found no plan while others moved plans again after this many events
#: (segments ending) at the latest (module docstring).
BLOCKED_WAKE_EVENTS = 6


def note_blocked(fleet: Fleet, o: ObjectState, poses: np.ndarray) -> None:
    """``o``'s planner found no plan with the objects at ``poses``: it waits from now on,
    and the objects standing in the space it needs are noted."""
    obj, ex = fleet.scene.objects[o.index], fleet.executor
    goal = obj.goal if o.detour is None else o.detour
    team = np.asarray(ex.robot_positions, float)[o.team, :2]
    o.blocked_in = needed_space(obj.shape, poses[o.index], goal, team,
                                fleet.scene.robot_radius, o.claim)
    o.blockers = fleet.inside(o.blocked_in, poses) - {o.index}
    o.blocked_at = (fleet.finished, fleet.counts["events"])
    o.looked_at = fleet.counts["events"]


def wake_blocked(fleet: Fleet) -> None:
    """The waiting planners of ``fleet`` whose wait is over (module docstring) plan again."""
    now, poses = fleet.counts["events"], None
    for o in fleet.objects:
        if o.blocked_at is None:
            continue
        finished, events = o.blocked_at
        left = False
        if o.blockers and now > o.looked_at:
            o.looked_at = now
            poses = fleet.executor.object_poses if poses is None else poses
            left = not o.blockers <= fleet.inside(o.blocked_in, poses)
        if fleet.finished > finished or now - events >= BLOCKED_WAKE_EVENTS or left:
            o.blocked_at, o.wake, o.ready = None, True, True
