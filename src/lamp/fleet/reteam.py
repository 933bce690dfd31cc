"""The fleet schedule's team changes: robots joining and leaving sub-teams between
segments. Part of the schedule's one writer (``coordinator.Fleet`` is built on
:class:`TeamChanges`): free robots reinforce moving teams (``teams.reinforce``), far robots
hand over to free ones nearer (``handover.better_team``), and a robot that fails leaves
its team for good, replaced by the nearest free robot (``teams.nearest``). Every change
goes through ``_reteam``, which logs it (and counts it, ``stats.COUNTS``).
"""

from __future__ import annotations

from collections.abc import Sequence

from lamp.contract.runner import WorldExecutor
from lamp.fleet.board import Board
from lamp.fleet.config import FleetConfig
from lamp.fleet.handover import better_team
from lamp.fleet.state import FAILED_ROBOT, FREE, ObjectState, ObjectStatus
from lamp.fleet.tasks import TaskFeed
from lamp.fleet.teams import nearest, reinforce
from lamp.scene.model import Scene

__all__ = ["TeamChanges"]


class TeamChanges(Board):
    """The team changes of the fleet schedule (module docstring), on its ``Board``."""

    def __init__(self, scene: Scene, executor: WorldExecutor, row_step: float,
                 config: FleetConfig, feed: TaskFeed, serial: bool = False) -> None:
        super().__init__(scene, executor, row_step, config, feed, serial)
        self._handover_checked: set[tuple[int, tuple[int, ...], tuple[int, ...]]] = set()

    def _reinforce(self) -> None:
        """Free robots join the moving teams with room within ``reinforce_reach``
        (``teams.reinforce``; not a blocked planner's: it takes them when it plans again),
        whose loops plan anew with them after their segment."""
        teams = {o.index: o.team for o in self.ranked() if o.status == ObjectStatus.ACTIVE
                 and o.team and o.blocked_at is None}
        for k, team in reinforce(self.free(), self.executor.robot_positions,
                                 self.executor.object_poses, teams,
                                 self.config.reinforce_reach).items():
            if team != self.objects[k].team:
                self._reteam(self.objects[k], team, "reinforced")

    def _hand_over(self) -> None:
        """Between its segments (a reply waits), a team's far robots give their places to
        free robots nearer by route (``handover.better_team``; checked once per team)."""
        for o in self.ranked():
            key = (o.index, tuple(o.team), tuple(self.free()))
            if (o.status != ObjectStatus.ACTIVE or o.reply is None
                    or key in self._handover_checked):
                continue
            self._handover_checked.add(key)
            team = better_team(self.scene, o.index, o.team, key[2], self.executor.robot_positions,
                               o.reply.object_poses[o.index], lambda: self.executor.object_poses)
            if team is not None:
                self._reteam(o, team, "handed_over")

    def _reteam(self, o: ObjectState, team: Sequence[int], what: str) -> None:
        """``o``'s sub-team becomes ``team`` (robots it loses go free); logged as ``what``,
        and counted when ``what`` is one of the schedule's counts."""
        self.stats.note(self.clock, what, o.index, f"{o.team} -> {sorted(team)}")
        self.owner[[i for i in o.team if self.owner[i] == o.index]] = FREE
        o.team = sorted(team)
        self.owner[o.team] = o.index
        if what in self.stats.counts:
            self.stats.count(what)

    def _note_failures(self) -> None:
        """Robots that failed in the last stretch (``executor.failed``) leave their teams
        for good, each replaced by the free robot nearest its object if any (the loop
        plans anew after its segment); every later plan has them as obstacles."""
        for i in sorted(self.executor.failed):
            if i in self.failed_at:
                continue
            self.failed_at[i] = self.clock
            k = int(self.owner[i])
            self.owner[i] = FAILED_ROBOT
            self.stats.note(self.clock, "failed", k, f"robot {i}")
            if k >= 0:
                o = self.objects[k]
                o.team = [j for j in o.team if j != i]
                if free := self.free():  # the nearest robot nobody needs takes its place
                    self._reteam(o, [*o.team, *nearest(free, self.executor.robot_positions,
                                                        self.executor.object_poses[k], 1)],
                                 "replaced")
