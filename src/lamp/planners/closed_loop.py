"""Closed-loop execution (paper Alg. 2 lines 3-7): until the goal, plan, execute in MuJoCo, observe, replan.

Every planner implements ``ObjectPlanner.plan(q_O, q_R, deadline) -> Plan`` for one
object; a :class:`ClosedLoop` (``run_object`` builds one from a task) drives it on an
:class:`Executor` (the MuJoCo ``Simulator``, or any object with its ``execute``) with a
policy that says when to replan:
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
from typing import Any, Protocol

import numpy as np

from lamp.contract.disturb import HEADING_PER_METRE
from lamp.contract.events import TRACE_EVERY, SegmentEvent
from lamp.contract.goals import (
    SUCCESS_ORIENTATION_TOL,
    SUCCESS_POSITION_TOL,
    goal_errors,
    within_goal,
)
from lamp.contract.plan import LoopPolicy, ObjectPlanner, PlanStatus
from lamp.contract.result import ObjectResult
from lamp.contract.robots import robots_match
from lamp.contract.runner import ALONE, Execution, Executor, LoopEnd, LoopHooks
from lamp.contract.trajectory import concat, straight_moves
from lamp.contract.transition import Transition
from lamp.geometry.se2 import pose_distance
from lamp.planners.config import PlannerConfig, segment_limit
from lamp.planners.long_push import merge, take_long_push
from lamp.planners.task import ManipulationTask, route_distance
from lamp.planners.watch import WATCH_FACTOR, WATCH_ROTATION, PushWatch, watched


@dataclass
class LoopRecord:
    """What the loop measured while moving one object."""

    planning_time_s: list[float] = field(default_factory=list)
    makespan: int = 0
    replans: int = 0
    #: Planning time after the last executed segment (a failed search, say): it belongs
    #: to no segment, so result.json reports it apart from ``planning_time_s``.
    unexecuted_planning_s: float = 0.0
    #: Pushes the watch stopped early (``lamp.planners.watch``).
    watch_stops: int = 0
    #: How the loop ended.
    end: LoopEnd = LoopEnd.FINISHED


#: Robot start positions that differ from a transition's by less than this are joined
#: with a short straight move; larger differences re-route the robots (Alg. 2 l. 27-33).
ROBOT_SNAP = 0.01

class Reroute(Protocol):
    """New approach paths for a verified push from robots at ``q_R`` (None: unreachable);
    ``Verifier.reroute`` is one."""

    def __call__(self, transition: Transition, q_R: np.ndarray) -> Transition | None: ...


def adapt_to_robots(trans: Transition, q_R: np.ndarray, reroute: Reroute) -> Transition | None:
    """``trans`` made to start from the robots at ``q_R``: unchanged when they stand at its
    start, joined by a short straight move when every robot is within ``ROBOT_SNAP`` of it,
    else re-routed: ``Reassign`` and Gspi anew (Alg. 2 lines 27-33; None when ``reroute``
    finds no approach)."""
    if robots_match(trans.robot_start, q_R, 1e-9):
        return trans
    if robots_match(trans.robot_start, q_R, ROBOT_SNAP):
        move = concat(straight_moves(q_R, trans.robot_start), trans.move)
        return Transition(trans.q_from, trans.q_to, trans.contacts, trans.pushes_local, move,
                          trans.manip, trans.edge)
    return reroute(trans, q_R)


#: A push achieving less than this share of its requested motion has stalled.
STALL_FRACTION = 0.25
#: ``failure_reason`` of a loop that ended with ``LoopEnd.TEAM_CHANGED``.
TEAM_CHANGED = "a robot failed"
#: ``failure_reason`` of a loop that ended with ``LoopEnd.WORLD_CHANGED``: its segment was
#: declined ...
WORLD_CHANGED = "the world changed around the plan"
#: ... or its planner found no plan and its host waited for the world to change.
NO_PLAN_YET = "no plan in the world as it stood"
#: Drift and stall tests keep this many standard deviations of the averaged reading above
#: the sensor's noise (``LoopConfig.sensing_sigma``).
NOISE_SIGMAS = 3.0
#: Before the loop stops at the goal under a noisy sensor it takes a closer look: this
#: many times ``sensing_readings`` fresh readings, whose mean must be within the stop
#: tolerances too (the averaged heading's noise halves at 4).
CONFIRM_FACTOR = 4


def _stalled(q_before: np.ndarray, q_after: np.ndarray, trans: Transition,
             noise: float = 0.0) -> bool:
    """Whether the push moved the object less than ``STALL_FRACTION`` of its request, beyond
    ``noise`` (the position noise of the difference of two readings)."""
    want_t, want_r = pose_distance(trans.q_from, trans.q_to)
    got_t, got_r = pose_distance(q_before, q_after)
    return bool(got_t < STALL_FRACTION * want_t + 1e-3 + noise
                and got_r < STALL_FRACTION * want_r + 2e-3 + noise * HEADING_PER_METRE)


@dataclass
class _Progress:
    """The loop's state between two steps."""

    q_O: np.ndarray
    q_R: np.ndarray
    pending: list[Transition] = field(default_factory=list)
    plan: Any = None
    planning_spent: float = 0.0
    #: Planning time not yet charged to an executed segment.
    pending_time: float = 0.0
    replanned: bool = False
    planned_once: bool = False
    full_horizon: bool = False
    segments: int = 0
    iterations: int = 0
    left: bool = False
    reason: str = ""
    #: ``segments`` when the stop was last confirmed by a closer look (-1: never)
    confirmed: int = -1


class ClosedLoop:
    """Alg. 2 lines 2-7 for one object: plan, execute, observe, until the goal or a limit.

    ``plan`` asks the planner when nothing is pending, ``execute`` runs the next transition
    (joined to where the robots are, see :func:`adapt_to_robots`, and extended into a long
    push) on the ``executor``, ``observe`` classifies the segment (``"continue"``,
    ``"left"``, ``"stalled"``, ``"drift"``) under the ``policy``. Guarantees (tested with
    fake executors): the loop stops as soon as the object is within the config's stop
    tolerances of ``goal``, after an object left the map, or after the segment limit;
    with ``replan_on_drift`` a segment missing its planned pose by more than the drift
    tolerances drops the rest of the plan; with ``replan_on_stall`` a push that barely moved
    the object is reported to the planner (``report_failure``); ``observer`` sees every
    executed segment, in order, and does not change the run.
    """

    def __init__(self, planner: ObjectPlanner, policy: LoopPolicy, executor: Executor, *,
                 index: int, goal: np.ndarray, config: PlannerConfig, reroute: Reroute,
                 record: LoopRecord | None = None,
                 observer: Callable[[SegmentEvent], None] | None = None,
                 clearance: Callable[[np.ndarray], float] | None = None,
                 reach: float = 0.0,
                 route: Callable[[np.ndarray], float] | None = None,
                 hooks: LoopHooks = ALONE) -> None:
        self.planner = planner
        self.hooks = hooks
        #: how far the object has to go from a pose (``task.route_distance``), which a
        #: scaled segment limit is measured on; None: the straight line
        self.route = route
        #: the object's clearance at a pose and its reach (farthest point from its origin),
        #: for the drift limits in tight places (``drift_limits``); None: the config's
        self.clearance = clearance
        self.reach = float(reach)
        self.policy = policy
        self.executor = executor
        self.index = int(index)
        self.goal = np.asarray(goal, float)
        self.config = config
        self.reroute = reroute
        self.record = LoopRecord() if record is None else record
        self.limit = config.loop.planning_time_limit
        self.observer = observer

    def run(self) -> ObjectResult:
        """Move the object to its goal; the :class:`ObjectResult` of the attempt."""
        cfg, goal = self.config, self.goal
        st = _Progress(np.asarray(self.executor.object_poses[self.index], float),
                       np.asarray(self.executor.robot_positions, float))
        max_segments = segment_limit(cfg.loop.max_segments, lambda: float(np.hypot(
            *(goal[:2] - st.q_O[:2]))) if self.route is None else self.route(st.q_O))
        while st.iterations < max_segments:
            if within_goal(st.q_O, goal, cfg.loop.stop_position, cfg.loop.stop_orientation):
                if not cfg.loop.sensing_sigma or st.confirmed == st.segments:
                    break
                st.q_O, st.confirmed = self._closer_look(), st.segments
                continue
            if not st.pending:
                step = self.plan(st)
                if step == "stop":
                    break
                if step == "retry":
                    continue
            trans = st.pending.pop(0)
            adapted = self._join(st, trans)
            if adapted is None:
                st.pending = []  # robots cannot reach this push from where they are: replan
                if not self.policy.replan_when_done and not self.policy.replan_on_drift:
                    st.reason = "robots cannot reach the next push (open loop)"
                    break
                continue
            executed = self.execute(st, adapted)
            if executed is None:  # declined by the executor (``Execution.declined``)
                self._end(st, LoopEnd.WORLD_CHANGED, WORLD_CHANGED)
                break
            if self.observe(st, *executed) in ("left", "team"):
                break
        return self._result(st, max_segments)

    def plan(self, st: _Progress) -> str:
        """Call the planner: ``"go"`` (transitions pending), ``"retry"`` (a failed call that
        costs one iteration) or ``"stop"`` (``st.reason`` says why)."""
        if st.planned_once and not self.policy.replan_when_done:
            st.reason = "plan finished away from the goal (open loop)"
            return "stop"
        remaining = self.limit - st.planning_spent
        if remaining <= 0:
            st.reason = "planning time limit"
            return "stop"
        t0 = time.perf_counter()
        st.plan = self.planner.plan(st.q_O, st.q_R, deadline=t0 + remaining)
        self._charge(st, time.perf_counter() - t0)
        if st.planned_once:
            self.record.replans += 1
        else:
            st.full_horizon = st.plan.solved and self.policy.full_horizon and not st.plan.partial
        st.planned_once = True
        st.replanned = True
        if st.plan.spent:  # no later call can plan: waiting or retrying would not help
            self._end(st, LoopEnd.FINISHED, st.plan.reason)
            return "stop"
        if not st.plan.solved:
            # a loop sharing its world (``lamp.fleet``) may wait for the world to change:
            # True, and the loop stops so that its runner plans anew
            if self.hooks.plan_failed():
                self._end(st, LoopEnd.WORLD_CHANGED, NO_PLAN_YET)
                return "stop"
            if self.policy.failure_is_final:
                end = LoopEnd.NO_PLAN if st.plan.status is PlanStatus.NO_PATH else LoopEnd.FINISHED
                self._end(st, end, st.plan.reason)
                return "stop"
            st.iterations += 1
            return "retry"
        st.pending = list(st.plan.transitions)
        return "go"

    def _join(self, st: _Progress, trans: Transition) -> Transition | None:
        """``trans`` from where the robots stand (re-routing counts as planning time)."""
        t0 = time.perf_counter()
        adapted = adapt_to_robots(trans, st.q_R, self.reroute)
        self._charge(st, time.perf_counter() - t0)
        return adapted

    def _end(self, st: _Progress, end: LoopEnd, reason: str) -> None:
        st.reason, self.record.end = reason, end

    @staticmethod
    def _charge(st: _Progress, dt: float) -> None:
        st.planning_spent += dt
        st.pending_time += dt

    def execute(self, st: _Progress, adapted: Transition
                ) -> tuple[Transition, Execution, float, bool] | None:
        """Run ``adapted`` (with the pushes that continue it) on the executor; returns the
        executed transition, the execution, and the planning time and replan flag charged
        to this segment; None when the executor declined it (nothing ran, nothing is
        counted).

        The hooks' ``announce`` is told first the object poses this segment plans to pass
        ((P, 3)) and those the plan goes on to ((R, 3)): the fleet schedule reserves space
        with them."""
        cfg = self.config
        chain = [adapted]
        if cfg.loop.long_push_length > 0:  # one approach, then every push that continues it
            chain = take_long_push(adapted, st.pending, cfg.loop.continuous_push_gap,
                                   cfg.loop.long_push_length, cfg.loop.long_push_turn)
            adapted = merge(chain)
        paths = adapted.robot_paths
        self.hooks.announce(np.array([chain[0].q_from, *[t.q_to for t in chain]], dtype=float),
                            np.array([t.q_to for t in st.pending], dtype=float).reshape(-1, 3))
        out = self.executor.execute(paths, record_every=TRACE_EVERY if self.observer else None,
                                    stop=self._watch(chain))
        if out.declined:
            return None
        st.iterations += 1
        st.segments += 1
        self.record.planning_time_s.append(st.pending_time)
        charged = (st.pending_time, st.replanned)
        st.pending_time, st.replanned = 0.0, False
        self.record.makespan += paths.shape[1] - 1
        return adapted, out, *charged

    def _watch(self, chain: list[Transition]) -> PushWatch | None:
        """The ``stop`` condition of a straight push through a tight place
        (``lamp.planners.watch``): ``WATCH_FACTOR`` times the position drift limit of its
        tightest planned pose, ``WATCH_ROTATION`` of turn; None for other pushes
        (``watch.watched``), without a clearance function, or when the policy does not
        replan on drift."""
        if self.clearance is None or not self.policy.replan_on_drift:
            return None
        poses = np.array([chain[0].q_from, *[t.q_to for t in chain]], dtype=float)
        tight = min(float(self.clearance(p)) for p in poses)
        if not watched(poses, tight):
            return None
        max_pos, _ = drift_limits(self.config, tight, self.reach)
        return PushWatch(poses, self.index, WATCH_FACTOR * max_pos, WATCH_ROTATION)

    def observe(self, st: _Progress, adapted: Transition, out: Execution, seg_time: float,
                seg_replanned: bool) -> str:
        """Read the executed segment's outcome and apply the policy; returns the outcome."""
        q_before = st.q_O
        st.q_O = self._read_pose(out)
        st.q_R = np.asarray(out.robot_positions, float)
        dpos, drot = pose_distance(st.q_O, adapted.q_to)
        cfg, policy = self.config, self.policy
        # the limits of the tighter of the pose reached and the next one planned (a push
        # into a passage must start aligned)
        tight = None
        if self.clearance is not None:
            tight = self.clearance(adapted.q_to)
            if st.pending:
                tight = min(tight, self.clearance(st.pending[0].q_to))
        max_pos, max_rot = drift_limits(cfg, tight, self.reach)
        floor = NOISE_SIGMAS * self._reading_sigma()  # drift within the noise is not drift
        max_pos, max_rot = max(max_pos, floor), max(max_rot, floor * HEADING_PER_METRE)
        stopped = out.stopped_at is not None  # by the watch
        outcome = "continue"
        if out.left_workspace:
            outcome = "left"
        elif self.hooks.team_changed():
            outcome = "team"  # a robot failed: the runner plans anew with the rest
        elif policy.replan_on_stall and _stalled(q_before, st.q_O, adapted,
                                                 NOISE_SIGMAS * np.sqrt(2) * self._reading_sigma()):
            outcome = "stalled"
        elif policy.replan_on_drift and (dpos > max_pos or drot > max_rot or stopped):
            outcome = "drift"
        if self.observer is not None:
            self.observer(SegmentEvent(self.index, st.segments - 1, adapted, out, st.plan,
                                       seg_time, seg_replanned, (float(dpos), float(drot)),
                                       outcome, self.record.replans))
        if outcome == "left":
            st.left = True
            st.reason = "object left the workspace"
        elif outcome == "team":
            self._end(st, LoopEnd.TEAM_CHANGED, TEAM_CHANGED)
        elif outcome == "stalled":
            # The push executed but barely moved the object: the verified transition does
            # not work in practice, so it is treated like a failed verification.
            self.planner.report_failure(adapted)
            st.pending = []
        elif outcome == "drift":
            st.pending = []  # line 6: drift -> replan from the observed state
            if stopped:
                # the watch stopped a push that left its path in a tight place
                # (``lamp.planners.watch``): it failed in practice, like a stall
                self.record.watch_stops += 1
                self.planner.report_failure(adapted)
        return outcome

    def _reading_sigma(self) -> float:
        """The position noise of one observation after averaging (0 for an exact sensor)."""
        cfg = self.config
        return cfg.loop.sensing_sigma / np.sqrt(cfg.loop.sensing_readings) if cfg.loop.sensing_sigma else 0.0

    def _read_pose(self, out: Execution) -> np.ndarray:
        """The object's observed pose after a segment: the execution's reading, averaged
        with ``sensing_readings - 1`` more of the settled object when the sensor is noisy."""
        first = np.asarray(out.object_poses[self.index], float)
        if not self.config.loop.sensing_sigma or self.config.loop.sensing_readings <= 1:
            return first
        return self._mean_reading([first], self.config.loop.sensing_readings - 1)

    def _closer_look(self) -> np.ndarray:
        """The settled object's pose from ``CONFIRM_FACTOR * sensing_readings`` fresh
        readings (the loop is about to stop on a noisy sensor's word)."""
        return self._mean_reading([], CONFIRM_FACTOR * self.config.loop.sensing_readings)

    def _mean_reading(self, reads: list[np.ndarray], more: int) -> np.ndarray:
        """The mean pose of ``reads`` and ``more`` fresh readings (circular in heading)."""
        arr = np.array(list(reads) + [np.asarray(self.executor.object_poses[self.index], float)
                                      for _ in range(more)])
        heading = np.arctan2(np.sin(arr[:, 2]).mean(), np.cos(arr[:, 2]).mean())
        return np.array([arr[:, 0].mean(), arr[:, 1].mean(), heading])

    def _result(self, st: _Progress, max_segments: int) -> ObjectResult:
        self.record.unexecuted_planning_s += st.pending_time
        q_O, goal = st.q_O, self.goal
        pos_err, rot_err = goal_errors(q_O, goal)
        success = (not st.left) and within_goal(q_O, goal, SUCCESS_POSITION_TOL,
                                                SUCCESS_ORIENTATION_TOL)
        reason = st.reason
        if not success and not reason:
            failed = st.iterations - st.segments  # GCo: a failed step counts like a segment
            reason = ((f"segment limit reached ({max_segments})" if failed <= 0 else
                       f"segment limit reached ({st.segments} segments and {failed} failed "
                       f"steps of {max_segments})")
                      if st.iterations >= max_segments else "stopped away from goal")
        return ObjectResult(
            success=bool(success), final_pose=[float(v) for v in q_O],
            goal=[float(v) for v in goal], position_error=pos_err, orientation_error=rot_err,
            left_workspace=bool(st.left), segments=st.segments,
            full_horizon_plan=bool(st.full_horizon), failure_reason="" if success else reason,
            replans=self.record.replans, planning_time_s=st.planning_spent,
        )


#: In tight places drift is tolerated up to this fraction of the planned pose's clearance,
#: and never below ``TIGHT_DRIFT_FLOOR`` (m) (at the object's farthest point).
TIGHT_DRIFT_FRACTION = 0.5
TIGHT_DRIFT_FLOOR = 0.01


def drift_limits(cfg: PlannerConfig, clearance: float | None, reach: float
                 ) -> tuple[float, float]:
    """(position, orientation) drift a segment may end with before the loop replans: the
    config's ``drift_position`` / ``drift_orientation``, tightened where the planned pose's
    ``clearance`` is small, so that no point of the object (``reach`` from its origin) has
    missed its planned place by more than ``TIGHT_DRIFT_FRACTION`` of the clearance (at
    least ``TIGHT_DRIFT_FLOOR``). Entering a corridor 2 cm wider than the object a few
    degrees askew jams it; replanning from the askew pose first realigns it."""
    if clearance is None or not reach > 0:
        return cfg.loop.drift_position, cfg.loop.drift_orientation
    allowed = max(TIGHT_DRIFT_FLOOR, TIGHT_DRIFT_FRACTION * float(clearance))
    return min(cfg.loop.drift_position, allowed), min(cfg.loop.drift_orientation, allowed / reach)


def run_object(task: ManipulationTask, planner: ObjectPlanner, policy: LoopPolicy, sim: Executor,
               record: LoopRecord,
               observer: Callable[[SegmentEvent], None] | None = None,
               hooks: LoopHooks = ALONE) -> ObjectResult:
    """Move ``task``'s object to its goal in ``sim`` with ``planner`` (Alg. 2 lines 2-7):
    a :class:`ClosedLoop` with the task's goal, config and ``Verifier.reroute``.

    ``observer``, when given, is called with a :class:`SegmentEvent` after every executed
    segment (in order); it only watches, the run is the same with or without it. ``hooks``:
    what the world around the loop adds (``lamp.contract.runner.LoopHooks``).
    """
    exact = task.exact_space
    loop = ClosedLoop(planner, policy, sim, index=task.index, goal=task.goal, config=task.config,
                      reroute=task.verifier.reroute, record=record, observer=observer,
                      clearance=exact.clearance, reach=exact.reach,
                      route=lambda q: route_distance(task.scene, task.index, q,
                                                     task.config.lattice.lattice_step), hooks=hooks)
    return loop.run()
