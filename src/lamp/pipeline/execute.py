"""A run without the warm-up: the request's object runner, one simulator, the schedule, the
recording and the result.

:func:`execute` is what :func:`lamp.pipeline.run` calls once the Numba kernels are loaded
(and what the warm-up itself runs). Every run is recorded: the recorder is the first
observer, and the result's ``makespan_s`` is the recording's last time.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from lamp.contract.events import RunObserver
from lamp.contract.result import RunResult
from lamp.contract.runner import ObjectOutcome, ObjectRunner
from lamp.pipeline.request import RunRequest
from lamp.pipeline.schedule import run_concurrently, run_in_order
from lamp.planners.series import judged
from lamp.scene.bounds import makespan_lower_bound
from lamp.scene.model import Scene

__all__ = ["KNOCKED", "execute", "object_runner", "still_placed"]

#: The failure reason of an object placed and later pushed off its goal.
KNOCKED = "pushed off its goal after it was placed"


def object_runner(request: RunRequest) -> ObjectRunner:
    """The object runner of ``request``'s planner: the closed loop with the request's model
    (loaded here) and parameters, or the planner's own (``PlannerSpec.runner``)."""
    spec = request.spec
    if spec.factory is None:
        return spec.runner(request.scene, request.params)
    from lamp.manip.models import load_proposer
    from lamp.planners.runner import ClosedLoopRunner

    return ClosedLoopRunner(request.scene, spec.factory, spec.policy,
                            load_proposer(request.model), request.params, request.seed)


def execute(request: RunRequest, observers: Sequence[RunObserver] = (),
            runner: ObjectRunner | None = None, feed: Any = None) -> RunResult:
    """Run ``request`` (see the module docstring); ``result.recording`` is the recording.

    ``runner``: an object runner built by the caller (MAPush with another policy, say)
    instead of :func:`object_runner`'s. ``feed``: where a lifelong run's tasks come from
    (a ``fleet.tasks.TaskFeed``, a live service's; default: the scene's ``tasks``). A
    scene with tasks, or a run with a feed, is lifelong: served by the fleet (its
    sequential schedule: one task at a time by the whole team, first come first served),
    and its result has ``tasks`` and ``lifelong``. ``wall_time_s`` runs from the
    simulator's construction to the last object (model loading excluded); observers only
    watch.
    """
    from lamp.record import Recorder
    from lamp.sim import Simulator

    scene = request.scene
    runner = object_runner(request) if runner is None else runner
    t_start = time.perf_counter()
    sim = Simulator(scene)
    executor = sim
    if request.disturbances.active:
        from lamp.sim.disturbed import DisturbedExecutor

        executor = DisturbedExecutor(sim, request.disturbances, request.seed)
    recorder = Recorder(scene, runner.row_dt_s)
    fleet_stats, records = None, None
    lifelong = bool(scene.tasks) or feed is not None
    if scene.schedule == "concurrent" or lifelong:
        outcomes, fleet_stats, records = run_concurrently(
            scene, executor, runner, recorder, request.fleet, observers, feed=feed,
            serial=scene.schedule == "sequential")
    else:
        outcomes = run_in_order(scene, executor, runner, [recorder, *observers])
    if not lifelong:
        outcomes = still_placed(scene, outcomes, executor.true_object_poses)
    result = RunResult(scene=scene.name, planner=request.planner, seed=int(request.seed))
    unexecuted = 0.0
    for o in outcomes:
        result.add_object(o.result, o.planning_time_s, o.makespan)
        unexecuted += o.unexecuted_planning_s
    result.wall_time_s = time.perf_counter() - t_start
    result.unexecuted_planning_time_s = unexecuted
    result.stats = runner.run_stats(outcomes)
    if fleet_stats is not None:
        result.stats["fleet"] = fleet_stats
    result.makespan_s = recorder.sim_time_s
    bound = makespan_lower_bound(scene)
    result.makespan_lower_bound_s = bound.seconds
    if lifelong:
        _lifelong(result, scene, bound.per_object, records or [], fleet_stats or {})
    result.params = request.param_values()
    result.disturbances = request.disturbances.to_dict()
    if request.disturbances.robot_failures:
        result.stats["failed_robots"] = {str(k): [round(float(v), 4) for v in place]
                                         for k, place in sorted(executor.failed.items())}
        result.disturbances["robot_failures_fired"] = [
            [k, round(t, 4)] for k, t in sorted(executor.fired.items())]
    result.recording = recorder.finish(request.planner, int(request.seed), result.to_dict())
    return result


def still_placed(scene: Scene, outcomes: Sequence[ObjectOutcome], poses: Any
                 ) -> list[ObjectOutcome]:
    """``outcomes`` judged on the final object poses ``poses`` (the true poses when the run
    ends; the paper's success criterion is the final pose): an object that reached its
    goal and was later pushed off it (by another object or robot) fails, with its pose at
    the end and the reason; every other outcome is kept as it is."""
    out = []
    for k, o in enumerate(outcomes):
        if o.result.success:
            end = judged(o, np.asarray(poses[k], float), np.asarray(scene.objects[k].goal, float))
            if not end.result.success:
                o = replace(end, result=replace(end.result, failure_reason=KNOCKED))
        out.append(o)
    return out


def _lifelong(result: RunResult, scene: Scene, first: Sequence[float], records: list[Any],
              fleet_stats: dict[str, Any]) -> None:
    """A lifelong run's tasks, figures and lower bound (``scene.tasks.chain_lower_bound``
    over the tasks after each object's first) in ``result``."""
    from lamp.fleet.tasks import lifelong_figures
    from lamp.scene.model import Task
    from lamp.scene.tasks import chain_lower_bound

    seen: set[int] = set()
    later = []
    for t in records:  # in release order: each object's first is its own goal
        if t.object in seen:
            later.append(Task(t.object, t.goal, t.release_s))
        seen.add(t.object)
    result.makespan_lower_bound_s = chain_lower_bound(scene, first, later)
    result.tasks = [t.to_dict() for t in records]
    result.lifelong = lifelong_figures(records, result.makespan_s,
                                       fleet_stats.get("utilisation"))
