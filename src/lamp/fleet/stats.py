"""The fleet schedule's figures: its counts and decision log (:class:`FleetStats`) and
robot-time by state (:class:`RobotTime`), what ``result.json`` reports as
``stats.fleet``. The coordinator owns one :class:`FleetStats` and hands it explicitly to
what counts.

:class:`RobotTime` charges every stretch of the shared clock to each robot: *working* (its
sub-team's segment runs; of that, *moving* when its rows moved it), *waiting* (in a
sub-team whose segment does not run) or *idle* (in none, or failed). Guarantee (tested
through ``Fleet.stats``): working + waiting + idle = the clock, for every robot.
"""

from __future__ import annotations

from collections import Counter, defaultdict
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from lamp.fleet.state import ObjectState

__all__ = ["COUNTS", "STATES", "FleetStats", "RobotTime"]

#: the states robot-time is charged to (``moving`` is a part of ``working``)
STATES = ("working", "moving", "waiting", "idle")
#: What the schedule counts (``FleetStats.counts``; ``events``: stretches of the shared
#: clock run).
COUNTS = ("admitted", "declined", "waited", "forced", "blocked", "merged", "grown",
          "reinforced", "replaced", "handed_over", "events", "transit_hops", "parking_moves",
          "made_way", "jammed", "halted", "knocked")


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


class FleetStats:
    """The schedule's counts (``COUNTS``), its decision log, the wall-clock time spent
    planning transit hops and parking moves, and the robots' time (:class:`RobotTime`)."""

    def __init__(self, n_robots: int) -> None:
        self.counts = dict.fromkeys(COUNTS, 0)
        #: (simulated time, what, object, detail) of every decision: for the curious
        self.log: list[tuple[float, str, int, str]] = []
        self.transit_planning_s = 0.0
        self.robot_time = RobotTime(n_robots)
        #: per waiting object, why its segments waited (``admission.meets_moving``'s
        #: answers, "running j" / "claim j") and how often
        self.waits: defaultdict[int, Counter[str]] = defaultdict(Counter)

    def count(self, what: str, n: int = 1) -> None:
        """Add ``n`` to count ``what`` (one of ``COUNTS``; ``KeyError`` otherwise)."""
        self.counts[what] += n

    def note(self, clock: float, what: str, k: int, detail: str) -> None:
        """Log a decision about object ``k`` at simulated time ``clock``; a segment that
        waits (``what`` "meets") is also counted by its reason (``waits``)."""
        self.log.append((clock, what, k, detail))
        if what == "meets":
            self.waits[k][detail] += 1

    def report(self, objects: Sequence[ObjectState], failed_at: Mapping[int, float],
               clock: float) -> dict[str, Any]:
        """The figures for ``result.json``: counts, per-object placement times, when robots
        failed, and the robots' utilisation over ``clock`` seconds: shares of robot-time
        working (their sub-team's segment runs), moving (working and driven), waiting (in
        a sub-team, its segment not running) and idle (in no sub-team); working + waiting
        + idle = 1; and ``waits``: per object, how often a segment of it met a running one
        or a claim (``admission.meets_moving``: "running j", "claim j"), most frequent
        first; together at least ``waited`` (a segment that also meets a standing body
        waits without counting there)."""
        return {
            **self.counts,
            "placed_at_s": [None if o.placed_at_s is None else round(o.placed_at_s, 4)
                            for o in objects],
            "robots_failed_at_s": {str(i): round(t, 4) for i, t in sorted(failed_at.items())},
            "transit_planning_s": round(self.transit_planning_s, 4),
            "utilisation": self.robot_time.shares(clock),
            "waits": [dict(self.waits[o.index].most_common()) for o in objects],
        }
