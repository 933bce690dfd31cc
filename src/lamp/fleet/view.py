"""A sub-team's window on the fleet: the executor its object's closed loop drives.

:class:`FleetView` is an :class:`~lamp.contract.runner.Executor` for object ``k``'s
sub-team: it reads the shared simulator's object poses and its own robots' positions, and
hands each segment to the fleet (``Fleet.submit``), which runs it beside the others and
answers with a :class:`FleetExecution` (or declines it). It also carries the two optional
hooks the closed loop calls: ``announce`` (the segment's planned object poses and the
rest of the plan) and ``plan_failed``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from lamp.fleet.coordinator import Fleet

__all__ = ["FleetExecution", "FleetView"]


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


class FleetView:
    """Object ``k``'s sub-team's executor (see the module docstring); its team is fixed
    when it is made (a new loop gets a new view)."""

    def __init__(self, fleet: Fleet, k: int) -> None:
        self.fleet = fleet
        self.k = k
        self.team = list(fleet.objects[k].team)

    @property
    def object_poses(self) -> np.ndarray:
        return self.fleet.executor.object_poses

    @property
    def robot_positions(self) -> np.ndarray:
        return np.asarray(self.fleet.executor.robot_positions, float)[self.team]

    @property
    def team_changed(self) -> bool:
        """Whether a robot of this view's team has failed, robots joined it
        (``Fleet._reinforce``) or took the places of far ones (``Fleet._hand_over``): its
        loop then ends with ``TEAM_CHANGED`` and the object plans anew with its new team."""
        now = self.fleet.objects[self.k].team
        return (any(i in self.fleet.failed_at for i in self.team)
                or set(now) != set(self.team))

    def announce(self, segment: np.ndarray, rest: np.ndarray) -> None:
        self.fleet.announce(self.k, segment, rest)

    def plan_failed(self) -> bool:
        return self.fleet.plan_failed(self.k)

    def execute(self, robot_paths: np.ndarray, record_every: int | None = None,
                stop: Callable[[np.ndarray], bool] | None = None) -> FleetExecution:
        return self.fleet.submit(self.k, np.asarray(robot_paths, float), stop, self.team)
