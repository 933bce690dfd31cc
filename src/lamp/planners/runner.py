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
from typing import Any

import numpy as np

from lamp.contract.events import TRACE_EVERY, SegmentEvent
from lamp.contract.plan import LoopPolicy, ObjectPlanner
from lamp.contract.runner import Executor, ObjectOutcome
from lamp.planners.closed_loop import LoopRecord, run_object
from lamp.planners.config import PlannerConfig
from lamp.planners.task import ManipulationTask
from lamp.planners.verifier import TaskStats
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

    def run_object(self, index: int, executor: Executor,
                   observe: Callable[[SegmentEvent], None]) -> ObjectOutcome:
        task = ManipulationTask(self.scene, index, np.asarray(executor.object_poses, float),
                                self.proposer, self.config, seed=self.seed * 1000 + index)
        record = LoopRecord()
        result = run_object(task, self.factory(task), self.policy, executor, record,
                            observer=observe)
        self.totals.add(task.stats)
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
