"""LAMP's object runner: each object moved by its own planner in the closed loop.

:class:`ClosedLoopRunner` is the :class:`~lamp.contract.runner.ObjectRunner` of every
closed-loop planner (LAMP-Lazy, LAMP-A*, the GCo baselines): for object ``k`` it builds a
:class:`~lamp.planners.task.ManipulationTask` from the poses the objects have now (seed
``1000 * seed + k``), a planner from the planner's factory, and runs
:func:`~lamp.planners.closed_loop.run_object` under the planner's loop policy. The run's
``stats`` add up the tasks' counters (:class:`~lamp.planners.verifier.TaskStats`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from lamp.contract.events import TRACE_EVERY, SegmentEvent
from lamp.contract.goals import (
    SUCCESS_ORIENTATION_TOL,
    SUCCESS_POSITION_TOL,
    goal_errors,
    within_goal,
)
from lamp.contract.plan import LoopPolicy, ObjectPlanner
from lamp.contract.runner import Executor, ObjectOutcome
from lamp.planners.closed_loop import TEAM_CHANGED, LoopRecord, run_object
from lamp.planners.config import PlannerConfig, segment_limit
from lamp.planners.task import ManipulationTask, route_distance
from lamp.planners.team import TeamView, team_scene
from lamp.planners.verifier import TaskStats
from lamp.scene.model import Scene
from lamp.sim.mjcf import TIMESTEP

__all__ = ["ClosedLoopRunner", "judged", "merged"]


class ClosedLoopRunner:
    """Moves a scene's objects one call at a time with ``factory``'s planners (see the
    module docstring); one instance per run."""

    row_dt_s = TRACE_EVERY * TIMESTEP

    def __init__(self, scene: Scene, factory: Callable[[ManipulationTask], ObjectPlanner],
                 policy: LoopPolicy, proposer: Any, config: PlannerConfig, seed: int) -> None:
        self.scene = scene
        self.factory = factory
        self.policy = policy
        self.proposer = proposer
        self.config = config
        self.seed = int(seed)
        self.totals = TaskStats()
        self.watch_stops = 0

    def run_object(self, index: int, executor: Executor,
                   observe: Callable[[SegmentEvent], None]) -> ObjectOutcome:
        if not hasattr(executor, "failed"):  # a plain executor: one closed loop
            return self.loop(self.scene, index, executor, self.config, observe)
        goal = np.asarray(self.scene.objects[index].goal, float)
        start = np.asarray(executor.object_poses[index], float)
        limit = segment_limit(self.config.max_segments, lambda: route_distance(
            self.scene, index, start, self.config.lattice_step))
        parts: list[ObjectOutcome] = []
        while True:  # one closed loop per team: a robot that fails ends it
            now = np.asarray(executor.robot_positions, float)
            failed = {k: now[k] for k in executor.failed}  # where they stand now
            alive = [i for i in range(self.scene.n_robots) if i not in failed]
            used = sum(p.result.segments for p in parts)
            config = replace(self.config, max_segments=max(1, limit - used))
            view = TeamView(executor, alive)
            parts.append(self.loop(team_scene(self.scene, alive, failed), index, view, config,
                                    observe))
            if not (view.team_changed and parts[-1].result.failure_reason == TEAM_CHANGED
                    and used + parts[-1].result.segments < limit):
                break
        return judged(merged(parts), executor.true_object_poses[index], goal)

    def loop(self, scene: Scene, index: int, executor: Executor, config: PlannerConfig,
             observe: Callable[[SegmentEvent], None]) -> ObjectOutcome:
        """One closed loop for object ``index`` of ``scene`` (its robots, obstacles and
        the objects where ``executor`` says they are) under ``config``."""
        task = ManipulationTask(scene, index, np.asarray(executor.object_poses, float),
                                self.proposer, config, seed=self.seed * 1000 + index)
        record = LoopRecord()
        result = run_object(task, self.factory(task), self.policy, executor, record,
                            observer=observe)
        self.totals.add(task.stats)
        task.close()
        self.watch_stops += record.watch_stops
        return ObjectOutcome(result, record.planning_time_s, record.makespan,
                             record.unexecuted_planning_s)

    def run_stats(self, outcomes: list[ObjectOutcome]) -> dict[str, Any]:
        unexecuted = 0.0
        for o in outcomes:
            unexecuted += o.unexecuted_planning_s
        return {**vars(self.totals), "unexecuted_planning_time_s": round(unexecuted, 6),
                "watch_stops": self.watch_stops,
                "failure_reasons": [o.result.failure_reason for o in outcomes]}


def merged(parts: list[ObjectOutcome]) -> ObjectOutcome:
    """One outcome for an object moved by successive teams: the last loop's verdict, every
    loop's segments, planning and makespan; each new team counts as a replan."""
    last = parts[-1].result
    result = replace(last, segments=sum(p.result.segments for p in parts),
                     replans=sum(p.result.replans for p in parts) + len(parts) - 1,
                     full_horizon_plan=parts[0].result.full_horizon_plan,
                     planning_time_s=sum(p.result.planning_time_s for p in parts))
    return ObjectOutcome(result, [t for p in parts for t in p.planning_time_s],
                         sum(p.makespan for p in parts),
                         sum(p.unexecuted_planning_s for p in parts))


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
