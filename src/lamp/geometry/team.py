"""The robot team's physical contract, owned here once: disk radius, the largest step
between two synchronised rows of a trajectory, and the speed the simulator drives at.

Every layer reads these: the scene format's default radius, the manipulation model's
contacts (``lamp.manip``), Gspi's output spacing and the planners' trajectories (rows at
most ``row_step`` apart, so a check at the rows is a check of the motion), and the
simulator's timing (one row takes ``row_time`` seconds for the fastest robot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["DEFAULT_TEAM", "RobotTeam"]


@dataclass(frozen=True)
class RobotTeam:
    """Disk robots of ``radius`` (m) following rows at most ``row_step`` (m) apart at
    ``speed`` (m/s)."""

    radius: float = 0.05
    row_step: float = 0.02
    speed: float = 0.25

    def __post_init__(self) -> None:
        for name in ("radius", "row_step", "speed"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"RobotTeam.{name} must be a positive number, got {value!r}")

    @property
    def row_time(self) -> float:
        """Seconds one row takes for the fastest robot (the makespan's step)."""
        return self.row_step / self.speed


#: The team every built-in scene, the shipped model and the simulator are made for.
DEFAULT_TEAM = RobotTeam()
