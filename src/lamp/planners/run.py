"""``lamp.solve``: plan and execute a whole scene with one planner, object after object."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lamp.planners.closed_loop import LoopPolicy, LoopRecord, run_object
from lamp.planners.config import PlannerConfig
from lamp.planners.result import RunResult
from lamp.planners.task import ManipulationTask, TaskStats
from lamp.scene.model import Scene

#: Planner names accepted by ``lamp run --planner`` (interfaces spec).
PLANNERS = ("lazy", "astar", "astar-replan", "gco-ori", "gco-var", "mapush")

POLICIES = {
    "lazy": LoopPolicy(replan_on_drift=True, replan_when_done=True),
    "astar": LoopPolicy(replan_on_drift=False, replan_when_done=False),
    "astar-replan": LoopPolicy(replan_on_drift=True, replan_when_done=True),
    "gco-ori": LoopPolicy(replan_on_drift=False, replan_when_done=True, full_horizon=False,
                          failure_is_final=False),
    "gco-var": LoopPolicy(replan_on_drift=False, replan_when_done=True, full_horizon=False,
                          failure_is_final=False),
}


def check_planner(name: str) -> str:
    if name not in PLANNERS:
        raise ValueError(f"unknown planner {name!r}; expected one of: {', '.join(PLANNERS)}")
    return name


def default_config(planner: str) -> PlannerConfig:
    """Per-planner defaults: LAMP-A* keeps the paper's 500 s cumulative limit."""
    if planner in ("astar", "astar-replan"):
        return PlannerConfig(planning_time_limit=500.0)
    return PlannerConfig(planning_time_limit=300.0)


def make_planner(name: str, task: ManipulationTask):
    if name == "lazy":
        from lamp.planners.lazy import LazyPlanner

        return LazyPlanner(task)
    if name in ("astar", "astar-replan"):
        from lamp.planners.lamp_astar import LampAStar

        return LampAStar(task)
    from lamp.planners.gco import GCoPlanner

    return GCoPlanner(task, inflation=0.2 if name == "gco-ori" else 0.0)


def load_proposer(model: str | Any = "learned"):
    """The manipulation model: ``"learned"`` (shipped checkpoint), ``"geometric"`` or an object."""
    if not isinstance(model, str):
        return model
    from lamp import manip

    if model == "learned":
        return manip.load_model()
    if model == "geometric":
        return manip.GeometricProposer()
    raise ValueError(f"unknown model {model!r}; expected 'learned' or 'geometric'")


@dataclass
class Solution:
    """``RunResult`` plus what only a renderer needs (animation frames)."""

    result: RunResult
    frames: list[Any] = field(default_factory=list)


def solve(scene: Scene, planner: str = "lazy", seed: int = 0, *, model: str | Any = "learned",
          config: PlannerConfig | None = None, render: bool = False,
          time_limit: float | None = None) -> RunResult:
    """Plan and execute ``scene`` with ``planner``; ``result.to_dict()`` is result.json."""
    return solve_with_frames(scene, planner, seed, model=model, config=config, render=render,
                             time_limit=time_limit).result


def solve_with_frames(scene: Scene, planner: str = "lazy", seed: int = 0, *,
                      model: str | Any = "learned", config: PlannerConfig | None = None,
                      render: bool = False, time_limit: float | None = None,
                      progress=None) -> Solution:
    """As ``solve``, also returning the animation frames when ``render`` is set."""
    from lamp.sim import Simulator

    check_planner(planner)
    if planner == "mapush":
        from lamp.planners.mapush import solve_mapush

        return solve_mapush(scene, seed, render=render, progress=progress)
    cfg = config or default_config(planner)
    proposer = load_proposer(model)
    t_start = time.perf_counter()
    sim = Simulator(scene)
    result = RunResult(scene=scene.name, planner=planner, seed=int(seed))
    totals = TaskStats()
    frames: list[Any] = []
    unexecuted = 0.0
    for index in range(len(scene.objects)):
        task = ManipulationTask(scene, index, np.asarray(sim.object_poses, float), proposer, cfg,
                                seed=int(seed) * 1000 + index)
        record = LoopRecord()
        obj = run_object(task, make_planner(planner, task), POLICIES[planner], sim, record,
                         render=render, time_limit=time_limit)
        result.objects.append(obj)
        result.planning_time_s.extend(record.planning_time_s)
        result.makespan += record.makespan
        result.replans += record.replans
        totals.add(task.stats)
        unexecuted += record.unexecuted_planning_s
        frames.extend(record.frames)
        if progress is not None:
            progress(index, obj)
    result.wall_time_s = time.perf_counter() - t_start
    result.stats = {**vars(totals), "unexecuted_planning_time_s": round(unexecuted, 6),
                    "failure_reasons": [o.failure_reason for o in result.objects]}
    return Solution(result, frames)
