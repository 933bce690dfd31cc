"""What the fleet schedule knows of each object (``Fleet.objects``): its status, sub-team,
claim, the segment it submitted or runs, and its thread's state."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import shapely

from lamp.contract.runner import ObjectOutcome
from lamp.fleet.segments import Segment
from lamp.fleet.view import FleetExecution

__all__ = ["FAILED", "FREE", "ObjectState"]

#: ``Fleet.owner`` of a robot in no sub-team, and of one that failed (it stays where it
#: stopped, an obstacle to every plan, and is never given to a team again).
FREE, FAILED = -1, -2


@dataclass
class ObjectState:
    """One object as the fleet schedule tracks it (``Fleet.objects``)."""

    index: int
    status: str = "waiting"  # waiting -> active -> placed | failed
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
    wake: bool = False  # the answer to ``plan_failed``
    needs_team: bool = False  # its thread waits for robots (``wait_for_team``)
    #: a pose to move to before its goal: it stands in a blocked object's way
    #: (``fleet.makeway``); None: none
    detour: np.ndarray | None = None
    lent_by: int | None = None  # the object whose robots it has for its detour
    rank: int = 1 << 30  # its priority: the order in which objects started (lower first)
    world_at: int = -1  # the event after which its loop took its world (``Fleet.world_taken``)
    outcome: ObjectOutcome | None = None
    placed_at_s: float | None = None

    @property
    def held_up(self) -> bool:
        """Whether it stands waiting: its segment submitted and not admitted, or its
        planner waiting for the world to change (it comes no nearer meanwhile)."""
        return self.running is None and (self.request is not None
                                         or self.blocked_at is not None)
