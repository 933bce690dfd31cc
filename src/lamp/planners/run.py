"""``lamp.solve``: plan and execute a whole scene with one planner, object after object."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from lamp.contract.result import RunResult
from lamp.planners import registry
from lamp.planners.closed_loop import LoopRecord, SegmentEvent, run_object
from lamp.planners.config import PlannerConfig, PlannerName
from lamp.planners.models import load_proposer as _load_proposer
from lamp.planners.task import ManipulationTask, TaskStats
from lamp.progress import EventKind, ProgressCallback, ProgressEvent
from lamp.scene.loader import SceneError
from lamp.scene.model import Scene
from lamp.warmup import ensure_warm


def __getattr__(name: str) -> Any:
    if name == "PLANNERS":  # planner names accepted by ``lamp run --planner`` (the registry's)
        return registry.names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def check_planner(name: str) -> str:
    """``name`` if it is a planner name; else ``ValueError`` with the names and a hint."""
    return registry.get(name).name


def default_config(planner: str) -> PlannerConfig:
    """Per-planner defaults: the planner's own cumulative limit (``PlannerSpec.planning_limit``)."""
    return PlannerConfig(planning_time_limit=registry.get(planner).planning_limit)


def make_planner(name: str, task: ManipulationTask):
    """The closed-loop planner ``name`` for ``task``'s object."""
    spec = registry.get(name)
    if spec.factory is None:
        raise ValueError(f"planner {name!r} runs whole scenes, not in the closed loop")
    return spec.factory(task)


def load_proposer(model: str | Path | Any = "learned") -> Any:
    """The manipulation model: ``"learned"``, ``"geometric"``, a checkpoint path or an object
    (see ``lamp.planners.models``)."""
    return _load_proposer(model)


def check_robot_radius(scene: Scene, proposer: Any) -> None:
    """Refuse a scene whose robots the manipulation model does not make contacts for
    (``proposer``: the model, or the radius it serves; None serves any).

    The model's contacts sit ``robot_radius`` (plus a gap) off the object, so robots of
    another size would fail every ``Collide`` check or touch the object before the push:
    a :class:`~lamp.scene.SceneError` naming ``robots.radius`` instead of a run that
    silently finds nothing.
    """
    want = (proposer if isinstance(proposer, (int, float)) or proposer is None
            else getattr(proposer, "robot_radius", None))
    if want is not None and abs(float(scene.robot_radius) - float(want)) > 1e-9:
        where = scene.source or scene.name
        reason = (f"the manipulation model makes contacts for robots of radius "
                  f"{float(want):g} m, got {float(scene.robot_radius):g}; use robots of radius "
                  f"{float(want):g} m (or train a model for yours: lamp model data/train)")
        raise SceneError(f"{where}: robots.radius: {reason}", path=scene.source,
                         field="robots.radius", reason=reason)


@dataclass
class Solution:
    """``RunResult`` plus what only a renderer needs (animation frames, the recording)."""

    result: RunResult
    frames: list[Any] = field(default_factory=list)
    recording: Any = None


def solve(scene: Scene | str | Path, planner: PlannerName = "lazy", seed: int = 0, *,
          model: str | Path | Any = "learned", config: PlannerConfig | None = None,
          render: bool = False, time_limit: float | None = None,
          progress: ProgressCallback | None = None) -> RunResult:
    """Plan and execute ``scene`` with ``planner``; ``result.to_dict()`` is result.json and
    ``result.recording`` the run's :class:`lamp.record.Recording`.

    See :func:`solve_with_frames` for the arguments.
    """
    return solve_with_frames(scene, planner, seed, model=model, config=config, render=render,
                             time_limit=time_limit, progress=progress).result


def solve_with_frames(scene: Scene | str | Path, planner: PlannerName = "lazy", seed: int = 0,
                      *, model: str | Path | Any = "learned",
                      config: PlannerConfig | None = None, render: bool = False,
                      time_limit: float | None = None,
                      progress: ProgressCallback | None = None) -> Solution:
    """As ``solve``, also returning the animation frames when ``render`` is set.

    ``scene``: a ``Scene``, a scene file path or a built-in scene name (``maze-07``). Numba kernels
    are compiled (or loaded from their disk cache) once per process before planning starts
    (``lamp.warmup.ensure_warm``): ``planning_time_s`` never includes compilation.
    """
    if isinstance(scene, (str, Path)):
        from lamp.suites.registry import resolve_scene

        scene = resolve_scene(scene)  # a scene file, or a built-in scene by name
    check_planner(planner)
    proposer = load_proposer(model)
    ensure_warm(progress)
    return run_scene(scene, planner, seed, proposer, config=config, render=render,
                     time_limit=time_limit, progress=progress)


def run_scene(scene: Scene, planner: str, seed: int, model: str | Path | Any, *,
              config: PlannerConfig | None = None, render: bool = False,
              time_limit: float | None = None,
              progress: ProgressCallback | None = None) -> Solution:
    """Plan and execute every object of ``scene`` in order (no warm-up; see ``solve``).

    Every run is recorded (``Solution.recording``, also ``result.recording``): the
    recording only observes, it does not change the run.
    """
    from lamp.planners.closed_loop import RENDER_EVERY
    from lamp.record import Recorder
    from lamp.sim import Simulator
    from lamp.sim.mjcf import TIMESTEP

    spec = registry.get(planner)
    if spec.runner is not None:
        return spec.runner(scene, int(seed), model=model, config=config, render=render,
                           time_limit=time_limit, progress=progress)
    cfg = config or default_config(planner)
    if time_limit is not None:  # the budgets that stand for the limit follow it
        if not float(time_limit) > 0:
            from lamp.errors import InputError

            raise InputError(f"time_limit: positive seconds, got {time_limit!r}")
        cfg = dataclasses.replace(cfg, planning_time_limit=float(time_limit))
    proposer = load_proposer(model)
    check_robot_radius(scene, proposer)
    t_start = time.perf_counter()
    sim = Simulator(scene)
    result = RunResult(scene=scene.name, planner=planner, seed=int(seed))
    totals = TaskStats()
    frames: list[Any] = []
    unexecuted = 0.0
    watch_stops = 0
    n = len(scene.objects)
    recorder = Recorder(scene, RENDER_EVERY * TIMESTEP)

    def emit(kind: EventKind, index: int, **kw: Any) -> None:
        if progress is not None:
            progress(ProgressEvent(kind, object_index=index, n_objects=n, **kw))

    def observe(event: SegmentEvent) -> None:
        recorder(event)
        emit("segment", event.object_index, segments=event.segment + 1,
             replans=event.replans)

    for index in range(n):
        task = ManipulationTask(scene, index, np.asarray(sim.object_poses, float), proposer, cfg,
                                seed=int(seed) * 1000 + index)
        record = LoopRecord()
        emit("object", index)
        obj = run_object(task, spec.factory(task), spec.policy, sim, record,
                         render=render, time_limit=time_limit, observer=observe)
        emit("object-done", index, segments=obj.segments, replans=obj.replans,
             success=obj.success)
        result.add_object(obj, record.planning_time_s, record.makespan)
        totals.add(task.stats)
        unexecuted += record.unexecuted_planning_s
        watch_stops += record.watch_stops
        frames.extend(record.frames)
    result.wall_time_s = time.perf_counter() - t_start
    result.unexecuted_planning_time_s = unexecuted
    result.stats = {**vars(totals), "unexecuted_planning_time_s": round(unexecuted, 6),
                    "watch_stops": watch_stops,
                    "failure_reasons": [o.failure_reason for o in result.objects]}
    result.recording = recorder.finish(planner, int(seed), result.to_dict())
    return Solution(result, frames, result.recording)
