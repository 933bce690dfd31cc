"""One object moved by several closed loops in turn, under one set of limits.

A loop ends for good or so that its runner plans anew (``contract.runner.LoopEnd``): a
robot of its team failed (the sequential runner under disturbances), or the world changed
around its plan (the fleet schedule). :class:`LoopSeries` is what both runners share:
each next loop gets the segments, LAMP-Lazy's per-object Verify budget and, when the
series has one, the cumulative planning time the earlier loops left; the series has run
out when its loops used the segment limit, or made as many loops as the limit allows, or
spent the planning limit (:func:`limit_reached`); the object's outcome merges the loops'
(:func:`merged`: each new loop counts as a replan) and is judged on the object's true
pose (:func:`judged`).
Guarantees tested in ``tests/test_fleet_parts.py`` and ``tests/test_series.py``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from lamp.contract.goals import (
    SUCCESS_ORIENTATION_TOL,
    SUCCESS_POSITION_TOL,
    goal_errors,
    within_goal,
)
from lamp.contract.runner import ObjectOutcome
from lamp.planners.config import PlannerConfig, segment_limit
from lamp.planners.task import route_distance
from lamp.scene.model import Scene

__all__ = ["LoopSeries", "judged", "limit_reached", "merged"]

#: The least planning time (s) a next loop is given, however little is left.
MIN_PLANNING_S = 1e-3


def limit_reached(segment_limit: int, segments: int, loops: int, planning_s: float,
                  planning_limit: float) -> str:
    """Which of an object's limits its loops have reached ("" if none): its segments, as
    many loops as segments, or its cumulative planning time."""
    if planning_s >= planning_limit:
        return "planning time limit"
    if segments >= segment_limit:
        return f"segment limit reached ({segment_limit})"
    if loops > segment_limit:
        return f"plan-anew limit reached ({segment_limit} loops)"
    return ""


def merged(parts: list[ObjectOutcome]) -> ObjectOutcome:
    """One outcome for an object moved by successive loops: the last loop's verdict and
    ending, every loop's segments, planning and makespan; each new loop counts as a
    replan."""
    last = parts[-1].result
    result = replace(last, segments=sum(p.result.segments for p in parts),
                     replans=sum(p.result.replans for p in parts) + len(parts) - 1,
                     full_horizon_plan=parts[0].result.full_horizon_plan,
                     planning_time_s=sum(p.result.planning_time_s for p in parts),
                     verify_calls=sum(p.result.verify_calls for p in parts),
                     search_expansions=sum(p.result.search_expansions for p in parts))
    return ObjectOutcome(result, [t for p in parts for t in p.planning_time_s],
                         sum(p.makespan for p in parts),
                         sum(p.unexecuted_planning_s for p in parts), end=parts[-1].end)


def judged(outcome: ObjectOutcome, true_pose: np.ndarray, goal: np.ndarray) -> ObjectOutcome:
    """``outcome`` with the final pose and success judged on the object's true pose (the
    loop saw it through a noisy sensor)."""
    r = outcome.result
    pos_err, rot_err = goal_errors(true_pose, goal)
    success = not r.left_workspace and within_goal(true_pose, goal, SUCCESS_POSITION_TOL,
                                                   SUCCESS_ORIENTATION_TOL)
    reason = "" if success else (r.failure_reason or "stopped away from goal (true pose)")
    result = replace(r, success=bool(success), final_pose=[float(v) for v in true_pose],
                     position_error=pos_err, orientation_error=rot_err, failure_reason=reason)
    return replace(outcome, result=result)


class LoopSeries:
    """An object's closed loops in turn (module docstring) under ``segment_limit``
    segments and, when given, ``planning_limit`` seconds of cumulative planning."""

    def __init__(self, segment_limit: int, planning_limit: float | None = None) -> None:
        self.segment_limit = int(segment_limit)
        self.planning_limit = planning_limit
        self.parts: list[ObjectOutcome] = []

    @classmethod
    def of(cls, scene: Scene, index: int, start: np.ndarray, config: PlannerConfig,
           planning: bool = False) -> LoopSeries:
        """The series for object ``index`` of ``scene`` standing at ``start``: the
        segment limit of ``config`` (``config.segment_limit``, scaled on the object's route
        when it sets none) and, with ``planning``, its planning time limit."""
        limit = segment_limit(config.loop.max_segments, lambda: route_distance(
            scene, index, np.asarray(start, float), config.lattice.lattice_step))
        return cls(limit, config.loop.planning_time_limit if planning else None)

    @property
    def segments(self) -> int:
        """Segments the loops so far executed."""
        return sum(p.result.segments for p in self.parts)

    @property
    def planning_s(self) -> float:
        """Planning time the loops so far spent (s)."""
        return sum(p.result.planning_time_s for p in self.parts)

    @property
    def verify_calls(self) -> int:
        """Verify calls the loops so far made."""
        return sum(p.result.verify_calls for p in self.parts)

    def config(self, base: PlannerConfig) -> PlannerConfig:
        """``base`` for the next loop: the segments left (at least 1), what is left of
        LAMP-Lazy's per-object Verify budget (``lazy_verify_calls``, at least 1: it bounds
        the object, not each loop) and, with a planning limit, the planning time left (at
        least ``MIN_PLANNING_S``). The searches' expansion budgets are ``base``'s for each
        loop (a new loop searches a new world from scratch). The counts are ``base``'s,
        not derived from the time left: that depends on the machine, the counts must not
        (a run stays the same on a loaded machine)."""
        left = max(1, self.segment_limit - self.segments)
        counts = dict(lazy_max_object_verify=max(1, base.lazy_verify_calls - self.verify_calls),
                      lazy_max_expansions=base.lazy_expansions)
        if self.planning_limit is None:
            return base.but(max_segments=left, **counts)
        return base.but(max_segments=left, planning_time_limit=max(
            MIN_PLANNING_S, self.planning_limit - self.planning_s),
            astar_max_expansions=base.astar_expansions, **counts)

    def add(self, outcome: ObjectOutcome) -> ObjectOutcome:
        """Record a loop's outcome; returns it."""
        self.parts.append(outcome)
        return outcome

    def ran_out(self) -> str:
        """The limit the loops reached (``limit_reached``; "" if none). With one, the last
        loop's failure reason becomes its name: the object's verdict names the limit, not
        the last loop's end."""
        why = limit_reached(self.segment_limit, self.segments, len(self.parts),
                            self.planning_s, self.planning_limit
                            if self.planning_limit is not None else float("inf"))
        if why:
            last = self.parts[-1]
            self.parts[-1] = replace(last, result=replace(last.result, failure_reason=why))
        return why

    def outcome(self, true_pose: np.ndarray, goal: np.ndarray) -> ObjectOutcome:
        """The object's outcome: the loops merged, judged on ``true_pose``."""
        return judged(merged(self.parts), np.asarray(true_pose, float),
                      np.asarray(goal, float))
