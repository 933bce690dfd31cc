"""What the fleet schedule knows of each object (``Fleet.objects``): its status, sub-team,
claim, the segment it submitted or runs, and its thread's state.

An object's status is a small state machine (:class:`ObjectStatus`, the allowed moves in
``TRANSITIONS``): ``waiting`` (not started) -> ``active`` (a sub-team moves it) ->
``placed`` or ``failed``; a waiting object may also fail without starting (an object it
waits for failed); a placed or failed object waits again when its next task is released
(``fleet.tasks``: lifelong scenes). :meth:`ObjectState.move_to` is the only way a status
changes, and an illegal move raises :class:`IllegalTransition`. Guarantee (``tests/test_fleet_state.py``):
every sequence of moves either follows ``TRANSITIONS`` or raises, leaving the state as it
was.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum

import numpy as np
import shapely

from lamp.contract.runner import ObjectOutcome
from lamp.fleet.segments import Segment
from lamp.fleet.view import FleetExecution

__all__ = ["FAILED_ROBOT", "FREE", "TRANSITIONS", "IllegalTransition", "ObjectState",
           "ObjectStatus"]

#: ``Fleet.owner`` of a robot in no sub-team, and of one that failed (it stays where it
#: stopped, an obstacle to every plan, and is never given to a team again).
FREE, FAILED_ROBOT = -1, -2


class ObjectStatus(StrEnum):
    """Where an object is in the schedule (module docstring)."""

    WAITING = "waiting"
    ACTIVE = "active"
    PLACED = "placed"
    FAILED = "failed"

    @property
    def done(self) -> bool:
        """Placed or failed: it moves no more unless a new task is released for it."""
        return self in (ObjectStatus.PLACED, ObjectStatus.FAILED)


#: The allowed moves between statuses.
TRANSITIONS: Mapping[ObjectStatus, frozenset[ObjectStatus]] = {
    ObjectStatus.WAITING: frozenset({ObjectStatus.ACTIVE, ObjectStatus.FAILED}),
    ObjectStatus.ACTIVE: frozenset({ObjectStatus.PLACED, ObjectStatus.FAILED}),
    ObjectStatus.PLACED: frozenset({ObjectStatus.WAITING}),
    ObjectStatus.FAILED: frozenset({ObjectStatus.WAITING}),
}


class IllegalTransition(RuntimeError):
    """A status move ``TRANSITIONS`` does not allow (a defect of the schedule)."""


@dataclass
class ObjectState:
    """One object as the fleet schedule tracks it (``Fleet.objects``)."""

    index: int
    status: ObjectStatus = ObjectStatus.WAITING
    team: list[int] = field(default_factory=list)
    claim: shapely.Geometry | None = None
    #: its claim's near part and its way (``regions.claims``), with the claim
    near: shapely.Geometry | None = None
    way: shapely.Geometry | None = None
    #: objects its claim does not bind: those inside it when its planner failed
    exempt: frozenset[int] = frozenset()
    announced: np.ndarray | None = None  # the next segment's planned poses
    request: Segment | None = None  # submitted, not admitted
    running: Segment | None = None
    reply: FleetExecution | None = None
    ready: bool = False  # its thread has something to resume with
    #: (objects finished, events) when its planner failed; None: not waiting on a change
    blocked_at: tuple[int, int] | None = None
    #: the space it needs (``teams.needed_space``) when its planner failed, and the
    #: objects standing in it then (their bodies or robots): one leaving wakes it
    blocked_in: shapely.Geometry | None = None
    blockers: frozenset[int] = frozenset()
    looked_at: int = -1  # the event at which it last looked whether one left
    replan: bool = False  # the answer to ``plan_failed``: plan anew (True) or go on alone
    needs_team: bool = False  # its thread waits for robots (``wait_for_team``)
    #: a pose to move to before its goal: it stands in a blocked object's way
    #: (``fleet.makeway``); None: none
    detour: np.ndarray | None = None
    lent_by: int | None = None  # the object whose robots it has for its detour
    #: the moving objects its loop plans as if at their goals (``fleet.follow``), and
    #: whether its next loop plans round them instead (a segment of its was declined)
    leaders: frozenset[int] = frozenset()
    follow_off: bool = False
    rank: int = 1 << 30  # its priority: the order in which objects started (lower first)
    world_at: int = -1  # the event after which its loop took its world (``Fleet.world_taken``)
    outcome: ObjectOutcome | None = None
    placed_at_s: float | None = None

    def move_to(self, status: ObjectStatus) -> None:
        """Its status becomes ``status``; :class:`IllegalTransition` (nothing changed)
        when ``TRANSITIONS`` does not allow the move."""
        status = ObjectStatus(status)
        if status not in TRANSITIONS[self.status]:
            raise IllegalTransition(f"object {self.index}: {self.status} -> {status} is not "
                                    f"a move of the fleet schedule")
        self.status = status

    def renew(self) -> None:
        """Its next task (lifelong scenes): it waits to start again (``move_to``), all of
        its last task forgotten but when it was placed."""
        self.move_to(ObjectStatus.WAITING)
        fresh = ObjectState(self.index, self.status, placed_at_s=self.placed_at_s)
        self.__dict__.update(vars(fresh))

    def resume(self, replan: bool = True) -> None:
        """Its thread goes on at its next turn, no longer waiting for a change; ``replan``
        is what its planner's ``plan_failed`` answers (plan anew, or go on alone)."""
        self.blocked_at, self.replan, self.ready = None, replan, True

    @property
    def unplaced(self) -> bool:
        """Waiting or active: it still has to reach its goal."""
        return not self.status.done

    @property
    def held_up(self) -> bool:
        """Whether it stands waiting: its segment submitted and not admitted, or its
        planner waiting for the world to change (it comes no nearer meanwhile)."""
        return self.running is None and (self.request is not None
                                         or self.blocked_at is not None)
