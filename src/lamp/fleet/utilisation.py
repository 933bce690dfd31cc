"""Robot-time by state in the fleet schedule: what ``result.json`` reports as utilisation.

:class:`RobotTime` charges every stretch of the shared clock to each robot: *working* (its
sub-team's segment runs; of that, *moving* when its rows moved it), *waiting* (in a
sub-team whose segment does not run) or *idle* (in none, or failed). Guarantee (tested
through ``Fleet.stats``): working + waiting + idle = the clock, for every robot.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from lamp.fleet.coordinator import Fleet

__all__ = ["STATES", "RobotTime", "schedule_stats"]

#: the states robot-time is charged to (``moving`` is a part of ``working``)
STATES = ("working", "moving", "waiting", "idle")


class RobotTime:
    """Robot-seconds by state for ``n_robots`` robots (see the module docstring)."""

    def __init__(self, n_robots: int) -> None:
        self.seconds = {k: np.zeros(n_robots) for k in STATES}

    def charge(self, running_teams: Sequence[Sequence[int]], owner: np.ndarray,
               paths: np.ndarray, sim_time: float) -> None:
        """Charge ``sim_time``: robots of ``running_teams`` work (and move where their rows
        in ``paths``, robots x rows x 2, moved them); others wait when ``owner`` (robot ->
        object, negative: none) gives them a team, else idle."""
        working = np.zeros(len(owner), bool)
        for team in running_teams:
            working[list(team)] = True
        self.seconds["working"][working] += sim_time
        self.seconds["waiting"][~working & (owner >= 0)] += sim_time
        self.seconds["idle"][~working & (owner < 0)] += sim_time
        steps = np.hypot(*np.moveaxis(np.diff(paths, axis=1), 2, 0)).sum(axis=1)
        self.seconds["moving"][working & (steps > 1e-6)] += sim_time

    def shares(self, clock: float) -> dict[str, float]:
        """Each state's share of all robots' time over ``clock`` seconds (4 decimals)."""
        n = len(self.seconds["working"])
        total = max(clock, 1e-9) * max(1, n)
        return {k: round(float(v.sum()) / total, 4) for k, v in self.seconds.items()}


def schedule_stats(fleet: Fleet) -> dict[str, Any]:
    """The schedule's figures for ``result.json``: counts, per-object placement times and
    the robots' utilisation: shares of robot-time working (their sub-team's segment runs),
    moving (working and driven), waiting (in a sub-team, its segment not running) and idle
    (in no sub-team); working + waiting + idle = 1."""
    return {
        **fleet.counts,
        "placed_at_s": [None if o.placed_at_s is None else round(o.placed_at_s, 4)
                        for o in fleet.objects],
        "robots_failed_at_s": {str(i): round(t, 4) for i, t in sorted(fleet.failed_at.items())},
        "transit_planning_s": round(fleet.transit_planning_s, 4),
        "utilisation": fleet.robot_time.shares(fleet.clock),
    }
