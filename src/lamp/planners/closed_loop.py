"""Closed-loop execution (paper Alg. 2 lines 3-7): until the goal, plan, execute in MuJoCo, observe, replan.

Every planner implements ``ObjectPlanner.plan(q_O, q_R, deadline) -> Plan`` for one
object; ``run_object`` drives it with a policy that says when to replan:
- ``replan_on_drift``: after a segment whose object pose misses the planned one by more
  than ``drift_position`` / ``drift_orientation`` (LAMP-Lazy, LAMP-A* replan);
- ``replan_when_done``: when the plan is used up but the object is not at its goal
  (LAMP-Lazy and GCo, whose "plan" is a single step).
Multi-object scenes run object by object; the other objects stay physical bodies.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from lamp.geometry.se2 import pose_distance
from lamp.planners.base import LoopPolicy, ObjectPlanner
from lamp.planners.config import segment_limit
from lamp.planners.long_push import merge, take_long_push
from lamp.planners.result import (
    SUCCESS_ORIENTATION_TOL,
    SUCCESS_POSITION_TOL,
    ObjectResult,
    goal_errors,
    within_goal,
)
from lamp.planners.robots import robots_match
from lamp.planners.task import ManipulationTask
from lamp.planners.trajectory import concat, straight_moves
from lamp.planners.verify import Transition, reroute


@dataclass
class LoopRecord:
    """What the loop measured while moving one object."""

    planning_time_s: list[float] = field(default_factory=list)
    makespan: int = 0
    replans: int = 0
    #: Planning time after the last executed segment (a failed search, say): it belongs
    #: to no segment, so result.json reports it apart from ``planning_time_s``.
    unexecuted_planning_s: float = 0.0
    frames: list[Any] = field(default_factory=list)


@dataclass(frozen=True)
class SegmentEvent:
    """One executed segment, as handed to ``run_object``'s ``observer`` right after it ran.

    ``execution`` is the simulator's result, with a ``trace`` sampled every
    ``RENDER_EVERY`` physics steps (its row 0 is the state before the segment);
    ``transition`` the (robot-adapted) transition that was executed; ``plan`` the plan in
    force (``object_path``, ``verified_edges``, ``penalised_edges``) or None;
    ``planning_time_s`` the planning time charged to this segment; ``replanned`` whether a
    plan call preceded it; ``drift`` the (position, orientation) miss of the reached pose
    against ``transition.q_to``; ``outcome`` what the loop did next: ``"continue"``,
    ``"drift"`` (replan), ``"stalled"`` (push reported failed, replan) or ``"left"``.
    """

    object_index: int
    segment: int
    transition: Transition
    execution: Any
    plan: Any
    planning_time_s: float
    replanned: bool
    drift: tuple[float, float]
    outcome: str
    #: Replans of this object so far (the first plan is not a replan).
    replans: int = 0


#: Robot start positions that differ from a transition's by less than this are joined
#: with a short straight move; larger differences re-route the robots (Alg. 2 l. 27-33).
ROBOT_SNAP = 0.01

#: Physics steps between recorded animation frames when rendering.
RENDER_EVERY = 40


def _adapt_to_robots(task: ManipulationTask, trans: Transition, q_R: np.ndarray) -> Transition | None:
    if robots_match(trans.robot_start, q_R, 1e-9):
        return trans
    if robots_match(trans.robot_start, q_R, ROBOT_SNAP):
        move = concat(straight_moves(q_R, trans.robot_start), trans.move)
        return Transition(trans.q_from, trans.q_to, trans.contacts, trans.pushes_local, move,
                          trans.manip, trans.edge)
    return reroute(task, trans, q_R)


#: A push achieving less than this share of its requested motion has stalled.
STALL_FRACTION = 0.25


def _stalled(q_before: np.ndarray, q_after: np.ndarray, trans: Transition) -> bool:
    want_t, want_r = pose_distance(trans.q_from, trans.q_to)
    got_t, got_r = pose_distance(q_before, q_after)
    return bool(got_t < STALL_FRACTION * want_t + 1e-3 and got_r < STALL_FRACTION * want_r + 2e-3)


def run_object(task: ManipulationTask, planner: ObjectPlanner, policy: LoopPolicy, sim,
               record: LoopRecord, render: bool = False, time_limit: float | None = None,
               observer: Callable[[SegmentEvent], None] | None = None) -> ObjectResult:
    """Move ``task``'s object to its goal in ``sim`` with ``planner`` (Alg. 2 lines 2-7).

    ``observer``, when given, is called with a :class:`SegmentEvent` after every executed
    segment (in order); it only watches, the run is the same with or without it.
    """
    cfg = task.config
    limit = cfg.planning_time_limit if time_limit is None else time_limit
    goal = task.goal
    planning_spent = 0.0
    pending: list[Transition] = []
    plan_obj = None
    pending_time = 0.0
    segments = 0
    iterations = 0
    left = False
    planned_once = False
    full_horizon = False
    reason = ""
    replanned = False
    q_O = np.asarray(sim.object_poses[task.index], float)
    q_R = np.asarray(sim.robot_positions, float)
    max_segments = segment_limit(cfg.max_segments, float(np.hypot(*(goal[:2] - q_O[:2]))))
    while iterations < max_segments:
        if within_goal(q_O, goal, cfg.stop_position, cfg.stop_orientation):
            break
        if not pending:
            if planned_once and not policy.replan_when_done:
                reason = "plan finished away from the goal (open loop)"
                break
            remaining = limit - planning_spent
            if remaining <= 0:
                reason = "planning time limit"
                break
            t0 = time.perf_counter()
            plan_obj = planner.plan(q_O, q_R, deadline=t0 + remaining)
            dt = time.perf_counter() - t0
            planning_spent += dt
            pending_time += dt
            if planned_once:
                record.replans += 1
            if not planned_once:
                full_horizon = plan_obj.solved and policy.full_horizon
            planned_once = True
            replanned = True
            if not plan_obj.solved:
                if policy.failure_is_final:
                    reason = plan_obj.reason
                    break
                iterations += 1
                continue
            pending = list(plan_obj.transitions)
        trans = pending.pop(0)
        t0 = time.perf_counter()
        adapted = _adapt_to_robots(task, trans, q_R)
        dt = time.perf_counter() - t0
        planning_spent += dt
        pending_time += dt
        if adapted is None:
            pending = []  # robots cannot reach this push from where they are: replan
            if not policy.replan_when_done and not policy.replan_on_drift:
                reason = "robots cannot reach the next push (open loop)"
                break
            continue
        if cfg.long_push_length > 0:  # one approach, then every push that continues it
            adapted = merge(take_long_push(adapted, pending, cfg.continuous_push_gap,
                                           cfg.long_push_length))
        paths = adapted.robot_paths
        q_before = q_O
        traced = render or observer is not None
        out = sim.execute(paths, record_every=RENDER_EVERY if traced else None)
        iterations += 1
        segments += 1
        record.planning_time_s.append(pending_time)
        seg_time, seg_replanned = pending_time, replanned
        pending_time, replanned = 0.0, False
        record.makespan += paths.shape[1] - 1
        q_O = np.asarray(out.object_poses[task.index], float)
        q_R = np.asarray(out.robot_positions, float)
        if render:
            record.frames.extend(_frames(task, out, plan_obj))
        dpos, drot = pose_distance(q_O, adapted.q_to)
        outcome = "continue"
        if out.left_workspace:
            outcome = "left"
        elif policy.replan_on_stall and _stalled(q_before, q_O, adapted):
            outcome = "stalled"
        elif policy.replan_on_drift and (dpos > cfg.drift_position or drot > cfg.drift_orientation):
            outcome = "drift"
        if observer is not None:
            observer(SegmentEvent(task.index, segments - 1, adapted, out, plan_obj, seg_time,
                                  seg_replanned, (float(dpos), float(drot)), outcome,
                                  record.replans))
        if outcome == "left":
            left = True
            reason = "object left the workspace"
            break
        if outcome == "stalled":
            # The push executed but barely moved the object: the verified transition does
            # not work in practice, so it is treated like a failed verification.
            planner.report_failure(adapted)
            pending = []
        elif outcome == "drift":
            pending = []  # line 6: drift -> replan from the observed state
    record.unexecuted_planning_s += pending_time
    pos_err, rot_err = goal_errors(q_O, goal)
    success = (not left) and within_goal(q_O, goal, SUCCESS_POSITION_TOL,
                                         SUCCESS_ORIENTATION_TOL)
    if not success and not reason:
        reason = (f"segment limit reached ({max_segments})" if iterations >= max_segments
                  else "stopped away from goal")
    return ObjectResult(
        success=bool(success), final_pose=[float(v) for v in q_O], goal=[float(v) for v in goal],
        position_error=pos_err, orientation_error=rot_err, left_workspace=bool(left),
        segments=segments, full_horizon_plan=bool(full_horizon),
        failure_reason="" if success else reason, replans=record.replans,
        planning_time_s=planning_spent,
    )


def _frames(task: ManipulationTask, out, plan_obj) -> list[Any]:
    from lamp.viz.animation import Frame

    trace = getattr(out, "trace", None)
    if trace is None:
        return []
    path = plan_obj.object_path if plan_obj is not None else None
    verified = plan_obj.verified_edges if plan_obj is not None else []
    penalised = plan_obj.penalised_edges if plan_obj is not None else []
    frames = []
    for robots, objects in zip(trace.robot_positions, trace.object_poses, strict=False):
        frames.append(Frame(robot_positions=robots, object_poses=objects, active_object=task.index,
                            planned_path=path, verified_edges=verified, penalised_edges=penalised,
                            caption=f"object {task.index + 1}/{len(task.scene.objects)}"))
    return frames
