"""The MAPush-style baseline (``mapush``): hierarchical, a path-following high level that
hands object subgoals to a learned, shared mid-level pushing policy.

High level (per subgoal): an obstacle-aware object path from the object's current pose to
its goal on the object lattice (GCo's weighted A*, ``lamp.search.gco_lattice``, no
inflation; a footprint shrunk by 2 cm as fallback next to obstacles), and the subgoal the
*lookahead* distance along it (the goal itself once the rest of the path is shorter).
Adaptive subgoal choice: the lookahead starts at ``lamp.rl.tasks.SUBGOAL_AHEAD``, halves
(down to ``LOOKAHEAD_MIN``) after a subgoal the policy did not reach in its time and grows
by half again (up to the start value) after one it reached.

Mid level: the PPO policy (``lamp.rl.policy``) drives all robots with velocity commands in
``lamp.env.PushCore`` on the run's own simulator, at the speed it was trained for (the
scene's ``robots.speed``: a scene at another speed is refused, ``check_scene``), until the
object is within ``SUBGOAL_TOLERANCE`` of the subgoal or the policy's subgoal time (its
training episodes' length, ``lamp.rl.tasks.SUBGOAL_TIME``) has passed.

An object's run ends when its position is within the strict 0.1 m of the goal, after
``OBJECT_TIME_LIMIT`` simulated seconds (MAPush's two minutes), when no object path exists,
or when the object leaves the workspace. Two criteria are recorded: the scene format's
(``success``: final pose within 0.1 m and 0.1 rad) and MAPush's (``mapush_success``: within
``MAPUSH_RADIUS`` of the goal position at some instant within the time limit, orientation
ignored).

Segments are subgoals; makespan counts ``MAKESPAN_STEP`` = 0.08 s steps of simulated time.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lamp.contract.events import TRACE_EVERY
from lamp.contract.goals import (
    SUCCESS_ORIENTATION_TOL,
    SUCCESS_POSITION_TOL,
    goal_errors,
    within_goal,
)
from lamp.contract.result import ObjectResult
from lamp.contract.runner import ObjectOutcome
from lamp.scene.model import Scene
from lamp.sim.mjcf import TIMESTEP
from lamp.sim.simulator import MAX_STEP, ROBOT_SPEED

#: Simulated time limit per object [s] (MAPush's criterion: two minutes).
OBJECT_TIME_LIMIT = 120.0
#: MAPush's success radius around the goal position [m] (orientation ignored).
MAPUSH_RADIUS = 0.5
#: Smallest lookahead of the adaptive subgoal choice [m].
LOOKAHEAD_MIN = 0.2
#: Simulated time of one makespan step (one 0.02 m waypoint at the simulator's speed) [s].
MAKESPAN_STEP = MAX_STEP / ROBOT_SPEED
#: The run of an object ends within this of the goal position [m] (the strict criterion).
STOP_RADIUS = SUCCESS_POSITION_TOL


def check_scene(scene: Scene, policy=None) -> None:
    """``lamp.errors.InputError`` (a ValueError) when the policy cannot drive ``scene``:
    another number of robots, or robots at another speed (``robots.speed``) than it was
    trained for (it would then drive them at its own, unlike every other planner)."""
    from lamp.errors import InputError
    from lamp.rl.policy import load_policy
    from lamp.rl.tasks import check_speed

    policy = policy or load_policy()
    if scene.n_robots != policy.info.n_robots:
        raise InputError(
            f"planner mapush: scene {scene.name!r} has {scene.n_robots} robots, but the "
            f"mid-level policy was trained for {policy.info.n_robots}"
        )
    try:
        check_speed([scene], policy.robot_speed, "planner mapush")
    except ValueError as exc:
        raise InputError(str(exc)) from None


@dataclass
class MapushRecord:
    """What one object's run measured (besides its ``ObjectResult``); ``observer`` (if
    set) is called with a ``lamp.contract.events.SegmentEvent`` of every
    subgoal (what ``lamp.record.Recorder`` takes)."""

    planning_time_s: list[float] = field(default_factory=list)
    makespan: int = 0
    mapush_success: bool = False
    mapush_time_s: float | None = None
    sim_time_s: float = 0.0
    observer: Any = None


def _segment_event(index: int, segment: int, rows: list, sub: np.ndarray, path: np.ndarray,
                   planning_s: float, period: float, every: int, outcome: str):
    """A subgoal as a segment record: its trace (states every ``every`` steps, row 0 the
    state before it), the requested object motion, no contacts (the policy chooses them)."""
    from types import SimpleNamespace

    from lamp.contract.events import SegmentEvent
    from lamp.sim.simulator import Trace

    steps = np.array([r[0] for r in rows], float)
    robots = np.array([r[1] for r in rows], float)
    objects = np.array([r[2] for r in rows], float)
    trace = Trace(times=(steps - steps[0]) * period, robot_positions=robots,
                  object_poses=objects)
    execution = SimpleNamespace(trace=trace, sim_time=float((steps[-1] - steps[0]) * period))
    q_from = objects[0, index]
    transition = SimpleNamespace(q_from=q_from, q_to=sub, contacts=np.zeros((0, 2)),
                                 pushes_local=np.zeros((0, 1, 2)))
    plan = SimpleNamespace(object_path=path, verified_edges=[], penalised_edges=[])
    miss = goal_errors(objects[-1, index], sub)
    return SegmentEvent(object_index=index, segment=segment, transition=transition,
                        execution=execution, plan=plan, planning_time_s=planning_s,
                        replanned=True, drift=miss, outcome=outcome, replans=segment)


def _object_path(scene: Scene, index: int, pose: np.ndarray, poses: np.ndarray):
    from lamp.search.gco_lattice import gco_object_path

    for shrink in (0.0, 0.02):
        path = gco_object_path(scene, index, pose, poses, -shrink, time_limit=10.0)
        if path is not None and len(path) > 0:
            return np.asarray(path, float)
    return None


def run_object(scene: Scene, index: int, sim, policy, record: MapushRecord,
               time_limit: float = OBJECT_TIME_LIMIT) -> ObjectResult:
    """Move object ``index`` to its goal in ``sim`` within ``time_limit`` simulated seconds
    (see the module docstring)."""
    from lamp.env.core import PushConfig, PushCore
    from lamp.env.gym_env import observation_space
    from lamp.rl.tasks import SUBGOAL_AHEAD, SUBGOAL_TOLERANCE, along, pose_at

    settings = {k: v for k, v in policy.info.env_settings.items()
                if k in ("frame_skip", "max_speed", "patch_size", "patch_spacing",
                         "patch_range", "frame")}
    # the core never ends an episode by itself: success is judged here
    config = PushConfig(**settings, position_tolerance=1e-9, orientation_tolerance=None,
                        time_limit=time_limit + 1.0)
    core = PushCore(scene, config, sim=sim)
    core.resume(active=index)
    obs_space = observation_space(core)
    policy.check_env(core.n_robots, obs_space, f"scene {scene.name!r}")
    goal = scene.objects[index].goal
    subgoal_time = policy.subgoal_time
    lookahead = SUBGOAL_AHEAD
    every = trace_stride(config.frame_skip)  # env steps per recorded state
    segments, reason, left = 0, "", False
    q = core.object_poses()[index]
    while True:
        if math.hypot(*(q[:2] - np.asarray(goal[:2]))) <= STOP_RADIUS:
            break
        if core.time >= time_limit - 1e-9:
            reason = f"time limit ({time_limit:g} s simulated)"
            break
        t0 = time.perf_counter()
        path = _object_path(scene, index, q, core.object_poses())
        dt = time.perf_counter() - t0
        if path is None:
            reason = "no object path"
            break
        rest = along(path)[-1]
        last = rest <= lookahead  # the subgoal is the goal: reached at STOP_RADIUS only
        sub = np.asarray(goal, float) if last else pose_at(path, lookahead)
        reach = STOP_RADIUS if last else SUBGOAL_TOLERANCE
        core.set_goal(sub)
        record.planning_time_s.append(dt)
        segments += 1
        t_sub = core.time
        rows = [(core.steps, core.robot_positions().copy(), core.object_poses())]
        reached = False
        while core.time - t_sub < subgoal_time - 1e-9 and core.time < time_limit - 1e-9:
            out = core.step(policy.act(obs_space, core.observe()))
            q = core.object_poses()[index]
            d_goal = math.hypot(*(q[:2] - np.asarray(goal[:2])))
            if not record.mapush_success and d_goal <= MAPUSH_RADIUS:
                record.mapush_success, record.mapush_time_s = True, core.time
            if out.info["left_workspace"]:
                left = True
            elif math.hypot(*(q[:2] - sub[:2])) <= reach or d_goal <= STOP_RADIUS:
                reached = True
            if core.steps % every == 0 or left or reached:
                rows.append((core.steps, core.robot_positions().copy(), core.object_poses()))
            if left or reached:
                break
        if rows[-1][0] != core.steps:
            rows.append((core.steps, core.robot_positions().copy(), core.object_poses()))
        if record.observer is not None and len(rows) > 1:
            outcome = "left" if left else ("continue" if reached else "stalled")
            record.observer(_segment_event(index, segments - 1, rows, sub, path, dt,
                                           core.period, every, outcome))
        if left:
            reason = "object left the workspace"
            break
        lookahead = (min(SUBGOAL_AHEAD, 1.5 * lookahead) if reached
                     else max(LOOKAHEAD_MIN, 0.5 * lookahead))
    record.sim_time_s += core.time
    record.makespan += int(round(core.time / MAKESPAN_STEP))
    pos_err, rot_err = goal_errors(q, goal)
    success = (not left) and within_goal(q, goal, SUCCESS_POSITION_TOL, SUCCESS_ORIENTATION_TOL)
    if not success and not reason:
        reason = "orientation off at the goal (the policy ignores orientation)"
    return ObjectResult(
        success=bool(success), final_pose=[float(v) for v in q], goal=[float(v) for v in goal],
        position_error=pos_err, orientation_error=rot_err, left_workspace=bool(left),
        segments=segments, full_horizon_plan=False, failure_reason="" if success else reason,
        replans=max(segments - 1, 0), planning_time_s=float(sum(record.planning_time_s)),
    )


def trace_stride(frame_skip: int) -> int:
    """Environment steps between recorded states: the closed loop's ``TRACE_EVERY`` physics
    steps, rounded to whole environment steps of ``frame_skip`` physics steps."""
    return max(1, round(TRACE_EVERY / int(frame_skip)))


class MapushRunner:
    """The :class:`~lamp.contract.runner.ObjectRunner` of ``mapush``: :func:`run_object` per
    object with the shipped (or a given) policy.

    Deterministic: nothing is random. The run's ``stats`` add the MAPush criterion:
    ``mapush_success`` (every object within ``MAPUSH_RADIUS`` of its goal position within
    ``time_limit`` simulated seconds per object) and, per object, ``mapush_objects``.
    """

    def __init__(self, scene: Scene, policy=None, time_limit: float | None = None) -> None:
        from lamp.rl.policy import load_policy

        self.scene = scene
        self.policy = policy or load_policy()
        check_scene(scene, self.policy)
        self.time_limit = OBJECT_TIME_LIMIT if time_limit is None else float(time_limit)
        frame_skip = int(self.policy.info.env_settings.get("frame_skip", 10))
        self.row_dt_s = trace_stride(frame_skip) * frame_skip * TIMESTEP

    def run_object(self, index: int, executor, observe) -> ObjectOutcome:
        record = MapushRecord(observer=observe)
        result = run_object(self.scene, index, executor, self.policy, record,
                            time_limit=self.time_limit)
        extra = {"mapush_success": record.mapush_success, "mapush_time_s": record.mapush_time_s,
                 "sim_time_s": round(record.sim_time_s, 3)}
        return ObjectOutcome(result, record.planning_time_s, record.makespan, extra=extra)

    def run_stats(self, outcomes: list[ObjectOutcome]) -> dict[str, Any]:
        per_object = [o.extra for o in outcomes]
        return {"mapush_success": all(o["mapush_success"] for o in per_object),
                "mapush_objects": per_object,
                "failure_reasons": [o.result.failure_reason for o in outcomes]}
