"""What :func:`lamp.mrmp.plan_paths` (Gspi) returns: the plan and how the call ended."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any

import numpy as np

__all__ = ["GspiStatus", "MRMPPlan"]


class GspiStatus(str, Enum):
    """How a :func:`plan_paths` call ended (``MRMPPlan.status``); ``reason`` says more."""

    SOLVED = "solved"
    #: A start (robot) outside the workspace, inside an obstacle beyond the tolerance, or
    #: overlapping another robot.
    INVALID_START = "invalid_start"
    #: The same for a goal.
    INVALID_GOAL = "invalid_goal"
    #: A goal that cannot be linked to the lattice or reached from any start, or no
    #: assignment reaching every goal.
    UNREACHABLE = "unreachable"
    #: The step budget (``max_steps``) was spent.
    STEP_BUDGET = "step_budget"
    #: No progress for ``stall_steps`` steps (deadlock or livelock).
    STALLED = "stalled"
    #: The wall-clock ``time_limit`` passed.
    TIME_LIMIT = "time_limit"


@dataclass
class MRMPPlan:
    """Result of :func:`plan_paths`.

    success: every goal reached by exactly one robot, all motions checked.
    paths: (N, T, 2) synchronised positions (row t of every robot is the same instant),
        consecutive rows at most ``max_spacing`` (0.02 m) apart; ``paths[:, 0]`` are the
        starts. On failure: the motion computed so far (never to be executed as a plan).
    goal_of: (N,) goal index per robot at the end, -1 for robots without a goal.
    reason: empty on success, else why it failed.
    iterations: Gspi time steps taken.
    time_s: wall-clock time of the call.
    stats: extra figures (lattice size, link counts, steps removed ...).
    status: how the call ended (``SOLVED`` exactly when ``success``); on several lattices,
        the last one's.
    """

    success: bool
    paths: np.ndarray
    goal_of: np.ndarray
    reason: str = ""
    iterations: int = 0
    time_s: float = 0.0
    stats: dict[str, Any] = field(default_factory=dict)
    status: GspiStatus = GspiStatus.SOLVED

    def __post_init__(self) -> None:
        if self.success != (self.status is GspiStatus.SOLVED):
            raise ValueError(f"success={self.success} contradicts status {self.status}")

    @property
    def n_steps(self) -> int:
        """Number of synchronised rows T."""
        return int(self.paths.shape[1])


# --------------------------------------------------------------------------------------
