"""What the fleet schedule knows, and the questions it answers without changing anything.

:class:`Board` holds the schedule's state: the objects (``state.ObjectState``), which
sub-team each robot is in (``owner``), the shared clock, the robots that failed, and the
counters (``stats.FleetStats``), and the tasks (``desk.TaskDesk``). Its methods only
read; ``coordinator.Fleet``, built on it (through ``reteam.TeamChanges``, its team
changes, ``follow.Following``, the leaders its objects follow, and ``knocked.Knocks``,
placed objects placed again), is the one writer. The rules of the schedule (``admission``, ``blocked``,
``makeway``, ``teams``, ``handover``) take what they need from here and return decisions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import shapely

from lamp.contract.runner import WorldExecutor
from lamp.fleet.admission import heeded_claims, standing_in
from lamp.fleet.config import FleetConfig
from lamp.fleet.desk import TaskDesk
from lamp.fleet.parking import needed_by_others
from lamp.fleet.precedence import goal_cuts
from lamp.fleet.regions import ClaimBlocks
from lamp.fleet.state import FREE, ObjectState, ObjectStatus
from lamp.fleet.stats import FleetStats
from lamp.fleet.tasks import TaskFeed
from lamp.fleet.view import FleetExecution
from lamp.scene.model import Scene
from lamp.sim.simulator import SETTLE_TIME

__all__ = ["Board"]


class Board:
    """The fleet schedule's state for ``scene`` moved on ``executor`` (module docstring):
    ``row_step`` is the common row grid (m), ``config`` the schedule's settings, ``feed``
    where the tasks come from; ``serial``: one object at a time, by the whole team, in
    the order the tasks were released (the first-come-first-served baseline).

    ``scene`` is the scene in force: each object's goal is its current task's.
    """

    def __init__(self, scene: Scene, executor: WorldExecutor, row_step: float,
                 config: FleetConfig, feed: TaskFeed, serial: bool = False) -> None:
        self.scene, self.executor, self.config = scene, executor, config
        self.desk = TaskDesk(feed, len(scene.objects))
        self.serial = serial
        self.grid = float(row_step)
        self.reach = [o.shape.bounding_radius + scene.robot_radius for o in scene.objects]
        #: rows a segment's robots hold at its end while others move: the settle time
        self.hold_rows = math.ceil(SETTLE_TIME * float(scene.physics.robot_speed) / self.grid
                                   - 1e-9)
        self.objects = [ObjectState(k) for k in range(len(scene.objects))]
        self.started = self.finished = 0  # objects started (their ranks), placed or given up
        self.clock = 0.0
        self.stats = FleetStats(scene.n_robots)
        self.made_way: set[tuple[int, int]] = set()  # (j, k): j made way for k (makeway)
        self.cuts = goal_cuts(scene, scene.object_starts())  # k starts after cuts[k] are done
        self.owner = np.full(scene.n_robots, FREE)  # robot -> object of its team (FREE, ...)
        #: robots that failed (``executor.failed``), and when
        self.failed_at: dict[int, float] = {}
        #: answers of ``admission.passes_ahead`` by the plans they compared
        self.passing: dict = {}
        self.claim_blocks = ClaimBlocks()  # the blocks the plans' claims are built of

    @property
    def events(self) -> int:
        """Stretches of the shared clock run so far."""
        return self.stats.counts["events"]

    def all_done(self) -> bool:
        return all(o.status.done for o in self.objects)

    def may_start(self, k: int) -> bool:
        """Whether object ``k`` may start: it has a task; for its first, its ``after``
        objects are placed and those its goal would cut are done (``fleet.precedence``);
        serially, no other object is active."""
        if self.desk.current[k] is None:
            return False
        if self.serial and any(o.status == ObjectStatus.ACTIVE for o in self.objects
                               if o.index != k):
            return False
        return not self.desk.first(k) or (
            all(self.objects[a].status == ObjectStatus.PLACED for a in self.after(k))
            and all(self.objects[j].status.done for j in self.cuts[k]))

    def after(self, k: int) -> tuple[int, ...]:
        """The objects whose placing object ``k``'s current task waits for: the scene's
        ``after`` for its first task, none for later ones."""
        return self.scene.objects[k].after if self.desk.first(k) else ()

    def any_waits(self, but: int | None = None) -> bool:
        """Whether an object (other than ``but``) waits to start or waits for robots."""
        return any(o.status == ObjectStatus.WAITING or o.needs_team for o in self.objects
                   if o.index != but)

    def ranked(self) -> list[ObjectState]:
        """The objects by priority: in the order they started (then the scene's)."""
        return sorted(self.objects, key=lambda o: (o.rank, o.index))

    def free(self) -> list[int]:
        """The robots in no sub-team that have not failed (ascending)."""
        return [int(i) for i in np.flatnonzero(self.owner == FREE)]

    def moving(self) -> int:
        """How many objects are active."""
        return sum(o.status == ObjectStatus.ACTIVE for o in self.objects)

    def team_of(self, k: int) -> list[int]:
        return self.objects[k].team

    def robot_failed(self, i: int) -> bool:
        return i in self.failed_at

    def detour_of(self, k: int) -> np.ndarray | None:
        return self.objects[k].detour

    def inside(self, region: shapely.Geometry, poses: np.ndarray | None = None
               ) -> frozenset[int]:
        """The objects whose body (at ``poses``, else as read now) or sub-team's robots
        stand in ``region`` (``admission.standing_in``)."""
        return standing_in(region, self.scene,
                           self.executor.object_poses if poses is None else poses,
                           self.executor.robot_positions,
                           {p.index: p.team for p in self.objects if p.unplaced})

    def claims_above(self, k: int) -> list[shapely.Geometry]:
        """The claims a segment of object ``k`` that does not move it (a transit hop) must
        not end deeper in: those of the objects ranked above it that bind it, whole
        (``admission.meets_moving`` with no way of its own)."""
        return [full for _, full, _ in heeded_claims(self.objects, self.objects[k], 0.0, 0.0)]

    def needed_by_others(self, k: int) -> shapely.Geometry | None:
        """What the unplaced objects other than ``k`` still need (``parking``)."""
        return needed_by_others(self.scene, self.objects, self.executor.object_poses, k)

    def reply(self, team: Sequence[int], **outcome: Any) -> FleetExecution:
        """A loop's reply: the objects as observed now and ``team``'s robots."""
        return FleetExecution(np.asarray(self.executor.object_poses, float),
                              np.asarray(self.executor.robot_positions, float)[team], **outcome)

    def report(self) -> dict[str, Any]:
        """The schedule's figures for ``result.json`` (``FleetStats.report``)."""
        return self.stats.report(self.objects, self.failed_at, self.clock)
