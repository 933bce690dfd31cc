"""A sub-team's window on the fleet: the executor its object's closed loop drives.

:class:`FleetView` is an :class:`~lamp.contract.runner.Executor` for object ``k``'s
sub-team: it reads the shared simulator's object poses and its own robots' positions, and
hands each segment to the fleet (``Fleet.submit``), which runs it beside the others and
answers with a :class:`FleetExecution` (or declines it). Its loop's hooks
(``lamp.contract.runner.LoopHooks``) tell the fleet each segment's planned object poses
and the rest of the plan (``announce``) and ask it what to do when a plan failed
(``plan_failed``). What it asks of the fleet is :class:`SharedWorld`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from lamp.contract.runner import LoopHooks, WorldExecutor
from lamp.planners.team import TeamView

__all__ = ["FleetExecution", "FleetView", "SharedWorld"]


@dataclass
class FleetExecution:
    """What a sub-team's executor reports after a segment (an ``Execution``)."""

    object_poses: np.ndarray
    robot_positions: np.ndarray
    left_workspace: bool = False
    trace: Any = None
    stopped_at: int | None = None
    sim_time: float = 0.0
    #: The segment was not run: the world changed around its plan.
    declined: bool = False


class SharedWorld(Protocol):
    """What a view asks of the fleet (``Fleet`` is one)."""

    @property
    def executor(self) -> WorldExecutor:
        """The shared simulator (or an executor wrapping it)."""
        ...

    def team_of(self, k: int) -> list[int]:
        """Object ``k``'s sub-team now."""
        ...

    def robot_failed(self, i: int) -> bool:
        """Whether robot ``i`` failed."""
        ...

    def announce(self, k: int, segment: np.ndarray, rest: np.ndarray) -> None: ...

    def plan_failed(self, k: int) -> bool: ...

    def submit(self, k: int, paths: np.ndarray, stop: Callable[[np.ndarray], bool] | None,
               team: Sequence[int]) -> FleetExecution: ...


class FleetView(TeamView):
    """Object ``k``'s sub-team's executor (see the module docstring), a
    :class:`~lamp.planners.team.TeamView` whose paths run beside the other teams'; its
    team is fixed when it is made (a new loop gets a new view)."""

    def __init__(self, fleet: SharedWorld, k: int) -> None:
        super().__init__(fleet.executor, fleet.team_of(k))
        self.fleet = fleet
        self.k = k
        #: objects its loop plans at other poses than theirs (object -> pose:
        #: ``fleet.follow``'s leaders at their goals); its own object is never one
        self.ghosts: dict[int, np.ndarray] = {}

    @property
    def object_poses(self) -> np.ndarray:
        """The objects' poses as read now, each of ``ghosts`` at its pose there."""
        poses = self.executor.object_poses
        if not self.ghosts:
            return poses
        poses = np.array(poses, float)
        for j, pose in self.ghosts.items():
            poses[j] = pose
        return poses

    @property
    def team_changed(self) -> bool:
        """Whether a robot of this view's team has failed, robots joined it
        (``Fleet._reinforce``) or took the places of far ones (``Fleet._hand_over``): its
        loop then ends with ``LoopEnd.TEAM_CHANGED`` and the object plans anew with its
        new team."""
        now = self.fleet.team_of(self.k)
        return (any(self.fleet.robot_failed(i) for i in self.team)
                or set(now) != set(self.team))

    @property
    def hooks(self) -> LoopHooks:
        """Its loop's hooks: the team changed, announce a segment, a plan failed."""
        return LoopHooks(team_changed=lambda: self.team_changed, announce=self.announce,
                         plan_failed=self.plan_failed)

    def announce(self, segment: np.ndarray, rest: np.ndarray) -> None:
        self.fleet.announce(self.k, segment, rest)

    def plan_failed(self) -> bool:
        return self.fleet.plan_failed(self.k)

    def execute(self, robot_paths: np.ndarray, record_every: int | None = None,
                stop: Callable[[np.ndarray], bool] | None = None) -> FleetExecution:
        return self.fleet.submit(self.k, np.asarray(robot_paths, float), stop, self.team)
