"""LAMP's object runner: each object moved by its own planner in the closed loop.

:class:`ClosedLoopRunner` is the :class:`~lamp.contract.runner.ObjectRunner` of every
closed-loop planner (LAMP-Lazy, LAMP-A*, the GCo baselines): for object ``k`` it builds a
:class:`~lamp.planners.task.ManipulationTask` from the poses the objects have now (seed
``1000 * seed + k``), a planner from the planner's factory, and runs
:func:`~lamp.planners.closed_loop.run_object` under the planner's loop policy; under
disturbances, one loop per team of the robots still working (``TeamView``), in a
:class:`~lamp.planners.series.LoopSeries` as the fleet schedule runs its loops. The run's
``stats`` add up the tasks' counters (:class:`~lamp.planners.task_stats.TaskStats`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from lamp.contract.events import TRACE_EVERY, SegmentEvent
from lamp.contract.plan import LoopPolicy, ObjectPlanner
from lamp.contract.runner import ALONE, Executor, LoopEnd, LoopHooks, ObjectOutcome, WorldExecutor
from lamp.planners.closed_loop import LoopRecord, run_object
from lamp.planners.config import PlannerConfig
from lamp.planners.series import LoopSeries
from lamp.planners.task import ManipulationTask
from lamp.planners.task_stats import TaskStats
from lamp.planners.team import TeamView, team_scene
from lamp.scene.model import Scene
from lamp.sim.mjcf import TIMESTEP

__all__ = ["ClosedLoopRunner"]


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

    def run_object(self, index: int, executor: WorldExecutor,
                   observe: Callable[[SegmentEvent], None]) -> ObjectOutcome:
        if not executor.disturbed:  # nothing fails: one closed loop
            return self.loop(self.scene, index, executor, self.config, observe)
        series = LoopSeries.of(self.scene, index, executor.object_poses[index], self.config)
        while True:  # one closed loop per team: a robot that fails ends it
            now = np.asarray(executor.robot_positions, float)
            failed = {k: now[k] for k in executor.failed}  # where they stand now
            alive = [i for i in range(self.scene.n_robots) if i not in failed]
            view = TeamView(executor, alive)
            last = series.add(self.loop(team_scene(self.scene, alive, failed), index, view,
                                        series.config(self.config), observe, view.hooks))
            if not (view.team_changed and last.end is LoopEnd.TEAM_CHANGED
                    and series.segments < series.segment_limit):
                break
        return series.outcome(executor.true_object_poses[index], self.scene.objects[index].goal)

    def loop(self, scene: Scene, index: int, executor: Executor, config: PlannerConfig,
             observe: Callable[[SegmentEvent], None], hooks: LoopHooks = ALONE
             ) -> ObjectOutcome:
        """One closed loop for object ``index`` of ``scene`` (its robots, obstacles and
        the objects where ``executor`` says they are) under ``config``, with ``hooks``
        (what the world around it adds, ``LoopHooks``)."""
        task = ManipulationTask(scene, index, np.asarray(executor.object_poses, float),
                                self.proposer, config, seed=self.seed * 1000 + index)
        record = LoopRecord()
        result = run_object(task, self.factory(task), self.policy, executor, record,
                            observer=observe, hooks=hooks)
        self.totals.add(task.stats)
        task.close()
        self.watch_stops += record.watch_stops
        result = replace(result, verify_calls=task.stats.verify_calls,
                         search_expansions=task.stats.search_expansions)
        return ObjectOutcome(result, record.planning_time_s, record.makespan,
                             record.unexecuted_planning_s, end=record.end)

    def run_stats(self, outcomes: list[ObjectOutcome]) -> dict[str, Any]:
        unexecuted = 0.0
        for o in outcomes:
            unexecuted += o.unexecuted_planning_s
        return {**vars(self.totals), "unexecuted_planning_time_s": round(unexecuted, 6),
                "watch_stops": self.watch_stops,
                "failure_reasons": [o.result.failure_reason for o in outcomes]}
