"""The closed loop (plan, execute, observe) against fake executors: no MuJoCo.

A scripted planner plans straight translations of the object towards its goal, the robots
riding along; the fake executors move the object exactly as planned, drift it sideways,
leave it where it is (a stall) or push it off the map. The loop's guarantees are checked
on what it reports (ObjectResult, the observer's SegmentEvents, the planner's calls).
"""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from lamp.contract.plan import LoopPolicy, Plan, PlanStatus
from lamp.contract.runner import ALONE, LoopEnd, LoopHooks
from lamp.contract.trajectory import MAX_STEP, straight_moves
from lamp.contract.transition import Transition
from lamp.planners.closed_loop import (
    NO_PLAN_YET,
    ROBOT_SNAP,
    WORLD_CHANGED,
    ClosedLoop,
    LoopRecord,
    SegmentEvent,
)
from lamp.planners.config import PlannerConfig

LAZY = LoopPolicy(replan_on_drift=True, replan_when_done=True, replan_on_stall=True)
DRIFT_ONLY = LoopPolicy(replan_on_drift=True, replan_when_done=True)
OPEN = LoopPolicy(replan_on_drift=False, replan_when_done=False)
CONFIG = PlannerConfig.of(long_push_length=0.0, planning_time_limit=60.0)
START = np.array([1.0, 1.0, 0.0])
GOAL = np.array([2.0, 1.0, 0.0])
ROBOTS = np.array([[0.7, 1.0], [0.7, 1.3]])


class StraightPlanner:
    """Plans the object in straight steps of at most ``step`` m to the goal; the robots
    stand still for the approach, then translate with the object (robot 0 carries exactly
    the object's motion, which the fakes read back)."""

    def __init__(self, goal: np.ndarray, step: float = 0.2) -> None:
        self.goal = np.asarray(goal, float)
        self.step = step
        self.calls: list[tuple[np.ndarray, np.ndarray]] = []
        self.failures: list[Transition] = []

    def plan(self, q_O, q_R, deadline=None) -> Plan:
        q_O, q_R = np.array(q_O, float), np.array(q_R, float)
        self.calls.append((q_O.copy(), q_R.copy()))
        dist = float(np.hypot(*(self.goal[:2] - q_O[:2])))
        n = max(1, math.ceil(dist / self.step - 1e-9))
        out = []
        for k in range(n):
            q_to = q_O + (self.goal - q_O) / (n - k)
            delta = q_to[:2] - q_O[:2]
            manip = straight_moves(q_R, q_R + delta)
            out.append(Transition(q_O, q_to, q_R.copy(), manip - q_O[None, None, :2],
                                  q_R[:, None, :].copy(), manip, edge=(k, k + 1)))
            q_O, q_R = q_to, q_R + delta
        return Plan(PlanStatus.SOLVED, out, [], [])

    def report_failure(self, transition: Transition) -> None:
        self.failures.append(transition)

    def clear(self) -> None:
        self.calls.clear()


class FakeExecutor:
    """Moves object 0 by ``effect(segment, planned_motion)``; the robots end where their
    paths end (plus ``robot_offset``); ``left_at``: the segment whose object leaves the map."""

    def __init__(self, effect=lambda seg, d: d, left_at: int | None = None,
                 robot_offset: float = 0.0) -> None:
        self.poses = START[None].copy()
        self.robots = ROBOTS.copy()
        self.effect = effect
        self.left_at = left_at
        self.robot_offset = robot_offset
        self.executed: list[np.ndarray] = []

    @property
    def object_poses(self) -> np.ndarray:
        return self.poses.copy()

    @property
    def robot_positions(self) -> np.ndarray:
        return self.robots.copy()

    def execute(self, robot_paths, record_every=None, stop=None):
        paths = np.asarray(robot_paths, float)
        assert np.all(np.linalg.norm(np.diff(paths, axis=1), axis=2) <= MAX_STEP + 1e-9)
        seg = len(self.executed)
        self.executed.append(paths)
        self.poses[0, :2] += self.effect(seg, paths[0, -1] - paths[0, 0])
        self.robots = paths[:, -1] + self.robot_offset
        left = self.left_at is not None and seg >= self.left_at
        if left:
            self.poses[0, 0] = -1.0  # off the map
        return SimpleNamespace(object_poses=self.poses.copy(), robot_positions=self.robots.copy(),
                               left_workspace=left, trace=None, stopped_at=None,
                               declined=False)


def exact(seg: int, d: np.ndarray) -> np.ndarray:
    return d


def drifting(n: int, side: float = 0.08):
    """The planned motion plus ``side`` m to its left in the first ``n`` segments."""
    def effect(seg: int, d: np.ndarray) -> np.ndarray:
        if seg >= n:
            return d
        return d + side * np.array([-d[1], d[0]]) / np.hypot(*d)
    return effect


def stalled(seg: int, d: np.ndarray) -> np.ndarray:
    return np.zeros(2)


def run(executor, policy=LAZY, config=CONFIG, planner=None, reroute=None, goal=GOAL,
        clearance=None, reach=0.0, route=None, hooks=ALONE):
    planner = planner or StraightPlanner(goal)
    events: list[SegmentEvent] = []
    record = LoopRecord()
    reroutes: list[np.ndarray] = []

    def default_reroute(trans, q_R):
        reroutes.append(np.array(q_R))
        return None

    loop = ClosedLoop(planner, policy, executor, index=0, goal=goal, config=config,
                      reroute=reroute or default_reroute, record=record, observer=events.append,
                      clearance=clearance, reach=reach, route=route, hooks=hooks)
    result = loop.run()
    return SimpleNamespace(result=result, events=events, record=record, planner=planner,
                           reroutes=reroutes)


def test_exact_executor_reaches_the_goal_in_the_planned_segments() -> None:
    out = run(FakeExecutor(exact))
    res = out.result
    assert res.success and not res.left_workspace and res.failure_reason == ""
    assert res.segments == 5 and res.replans == 0 and len(out.planner.calls) == 1
    assert np.allclose(res.final_pose, GOAL)
    assert [e.segment for e in out.events] == list(range(5))
    assert [e.outcome for e in out.events] == ["continue"] * 5
    assert [e.replanned for e in out.events] == [True] + [False] * 4
    assert all(e.drift[0] < 1e-9 for e in out.events)
    assert out.record.makespan == sum(e.transition.robot_paths.shape[1] - 1 for e in out.events)
    assert len(out.record.planning_time_s) == 5 and not out.reroutes


def test_already_at_the_goal_plans_nothing() -> None:
    ex = FakeExecutor(exact)
    out = run(ex, goal=START)
    assert out.result.success and out.result.segments == 0
    assert out.planner.calls == [] and ex.executed == []


def test_long_pushes_join_transitions_into_one_segment() -> None:
    cfg = CONFIG.but(long_push_length=0.4)
    ex = FakeExecutor(exact)
    out = run(ex, config=cfg)
    assert out.result.success and out.result.segments == 3  # 0.4 + 0.4 + 0.2 m
    assert [len(p[0]) for p in ex.executed] == [e.transition.robot_paths.shape[1]
                                                for e in out.events]


def test_drift_replans_from_the_observed_pose() -> None:
    ex = FakeExecutor(drifting(2))
    out = run(ex, policy=DRIFT_ONLY)
    res = out.result
    assert [e.outcome for e in out.events][:3] == ["drift", "drift", "continue"]
    assert res.success and res.replans == 2 and len(out.planner.calls) == 3
    # every replan starts where the object and the robots were observed
    for event, (q_O, q_R) in zip(out.events[:2], out.planner.calls[1:], strict=True):
        assert np.allclose(q_O, event.execution.object_poses[0])
        assert np.allclose(q_R, event.execution.robot_positions)
    assert all(abs(e.drift[0] - 0.08) < 1e-9 for e in out.events[:2])
    assert [e.replans for e in out.events][:3] == [0, 1, 2]


def test_open_loop_keeps_executing_through_drift() -> None:
    out = run(FakeExecutor(drifting(2)), policy=OPEN)
    res = out.result
    assert res.segments == 5 and len(out.planner.calls) == 1
    assert [e.outcome for e in out.events] == ["continue"] * 5
    assert not res.success and res.failure_reason == "plan finished away from the goal (open loop)"
    assert np.allclose(res.final_pose, GOAL + [0.0, 0.16, 0.0])


def test_stall_is_reported_to_the_planner_until_the_segment_limit() -> None:
    cfg = CONFIG.but(max_segments=4)
    ex = FakeExecutor(stalled)
    out = run(ex, config=cfg)
    res = out.result
    assert [e.outcome for e in out.events] == ["stalled"] * 4
    assert [id(t) for t in out.planner.failures] == [id(e.transition) for e in out.events]
    assert res.segments == 4 and res.replans == 3 and not res.success
    assert res.failure_reason == "segment limit reached (4)"
    assert np.allclose(res.final_pose, START)


@pytest.mark.parametrize("route", [None, 5.0])
def test_a_scaled_segment_limit_is_measured_on_the_route(route) -> None:
    """Without ``max_segments`` the limit scales with the route the loop is given (here
    5 m: 150 segments), else with the straight line (1 m: the paper's 100)."""
    asked: list[np.ndarray] = []

    def distance(q):
        asked.append(np.array(q))
        return route

    out = run(FakeExecutor(stalled), config=CONFIG.but(max_segments=None),
              route=None if route is None else distance)
    limit = 100 if route is None else 150
    assert out.result.segments == limit
    assert out.result.failure_reason == f"segment limit reached ({limit})"
    assert len(asked) == (0 if route is None else 1) and all(np.allclose(q, START) for q in asked)


def test_stall_without_its_policy_reads_as_drift() -> None:
    cfg = CONFIG.but(max_segments=3)
    out = run(FakeExecutor(stalled), policy=DRIFT_ONLY, config=cfg)
    assert [e.outcome for e in out.events] == ["drift"] * 3
    assert out.planner.failures == [] and out.result.replans == 2


def test_object_pushed_out_ends_the_run() -> None:
    ex = FakeExecutor(exact, left_at=1)
    out = run(ex)
    res = out.result
    assert len(ex.executed) == 2 and res.segments == 2
    assert [e.outcome for e in out.events] == ["continue", "left"]
    assert res.left_workspace and not res.success
    assert res.failure_reason == "object left the workspace"


@pytest.mark.parametrize("final", [True, False])
def test_failed_plans(final: bool) -> None:
    class Failing(StraightPlanner):
        def plan(self, q_O, q_R, deadline=None) -> Plan:
            self.calls.append((q_O, q_R))
            return Plan.failed(PlanStatus.NO_PATH)

    policy = dataclasses.replace(LAZY, failure_is_final=final)
    cfg = CONFIG.but(max_segments=3)
    out = run(FakeExecutor(exact), policy=policy, config=cfg, planner=Failing(GOAL))
    assert out.result.segments == 0 and not out.result.success
    assert len(out.planner.calls) == (1 if final else 3)
    assert out.result.failure_reason == ("no plan found" if final else
                                        "segment limit reached (0 segments and 3 failed steps of 3)")


@pytest.mark.parametrize("fails", [True, False])
def test_a_loop_that_waits_for_the_world_says_why(fails: bool) -> None:
    """A loop sharing its world ends ``WORLD_CHANGED`` when its host waits for a change:
    after a failed plan its reason is ``NO_PLAN_YET`` (the fleet plans nearer then),
    after a declined segment ``WORLD_CHANGED``."""
    class Failing(StraightPlanner):
        def plan(self, q_O, q_R, deadline=None) -> Plan:
            self.calls.append((q_O, q_R))
            return Plan.failed(PlanStatus.BUDGET_EXHAUSTED)

    class Declining(FakeExecutor):
        def execute(self, robot_paths, record_every=None, stop=None):
            return SimpleNamespace(declined=True)

    waits: list[int] = []
    hooks = LoopHooks(plan_failed=lambda: waits.append(1) or True)
    out = (run(FakeExecutor(exact), planner=Failing(GOAL), hooks=hooks) if fails else
           run(Declining(exact), hooks=hooks))
    assert out.record.end is LoopEnd.WORLD_CHANGED and out.result.segments == 0
    assert out.result.failure_reason == (NO_PLAN_YET if fails else WORLD_CHANGED)
    assert waits == ([1] if fails else [])


def test_robots_off_the_plan_are_joined_or_rerouted() -> None:
    # within ROBOT_SNAP: a straight join, no re-route; the run still succeeds
    out = run(FakeExecutor(exact, robot_offset=0.5 * ROBOT_SNAP), policy=OPEN)
    assert out.result.success and out.reroutes == []
    # farther: re-routed; an open loop that cannot re-route stops
    out = run(FakeExecutor(exact, robot_offset=0.05), policy=OPEN)
    assert len(out.reroutes) == 1 and out.result.segments == 1
    assert out.result.failure_reason == "robots cannot reach the next push (open loop)"
    # a closed loop replans from where the robots are
    out = run(FakeExecutor(exact, robot_offset=0.05), policy=DRIFT_ONLY)
    assert out.result.success and len(out.reroutes) == len(out.planner.calls) - 1 >= 1


@settings(max_examples=25, deadline=None)
@given(dx=st.floats(-1.5, 1.5), dy=st.floats(-1.5, 1.5), step=st.floats(0.1, 0.4),
       side=st.floats(0.06, 0.2), n_drift=st.integers(0, 3))
def test_drift_then_exact_always_arrives(dx, dy, step, side, n_drift) -> None:
    """Whatever the first segments' drift, replanning on drift reaches the goal once the
    execution is exact; every drifting segment is one replan, and the observer does not
    change the run."""
    goal = START + [dx, dy, 0.0]
    dist = float(np.hypot(dx, dy))
    # on the stop distance itself the loop's own sum (goal - pose, rounded) may fall on
    # either side of it
    assume(abs(dist - CONFIG.loop.stop_position) > 1e-9)
    watched = run(FakeExecutor(drifting(n_drift, side)), policy=DRIFT_ONLY,
                  planner=StraightPlanner(goal, step), goal=goal)
    ex = FakeExecutor(drifting(n_drift, side))
    blind = ClosedLoop(StraightPlanner(goal, step), DRIFT_ONLY, ex, index=0, goal=goal,
                       config=CONFIG, reroute=lambda t, q: None).run()
    res = watched.result
    drifts = [e for e in watched.events if e.outcome == "drift"]
    assert res.success
    if dist <= CONFIG.loop.stop_position:  # already there: nothing planned, nothing executed
        assert res.segments == 0 and res.replans == 0
    else:
        assert np.allclose(res.final_pose, goal, atol=1e-9)
        assert res.replans == len(drifts) == n_drift
        assert [e.outcome for e in watched.events[n_drift:]] == ["continue"] * (
            res.segments - n_drift)
        if n_drift == 0:
            assert res.segments == math.ceil(dist / step - 1e-9)
    a, b = dataclasses.asdict(res), dataclasses.asdict(blind)
    a.pop("planning_time_s"), b.pop("planning_time_s")
    assert a == b


def test_drift_limits_tighten_with_the_clearance() -> None:
    """The config's limits in the open; in a tight place no point of the object may miss
    its planned place by more than half the clearance (at least TIGHT_DRIFT_FLOOR)."""
    from lamp.planners.closed_loop import TIGHT_DRIFT_FLOOR, drift_limits

    cfg = CONFIG
    assert drift_limits(cfg, None, 0.3) == (cfg.loop.drift_position, cfg.loop.drift_orientation)
    assert drift_limits(cfg, 1.0, 0.3) == (cfg.loop.drift_position, cfg.loop.drift_orientation)
    pos, rot = drift_limits(cfg, 0.04, 0.5)
    assert pos == pytest.approx(0.02) and rot == pytest.approx(0.04)
    assert drift_limits(cfg, 0.0, 0.5) == (TIGHT_DRIFT_FLOOR, TIGHT_DRIFT_FLOOR / 0.5)


def test_a_small_drift_in_a_tight_place_replans() -> None:
    """2 cm to the side: tolerated in the open (the 5 cm limit), a replan where the planned
    poses have 1 cm of clearance."""
    open_run = run(FakeExecutor(drifting(1, side=0.02)))
    assert [e.outcome for e in open_run.events].count("drift") == 0
    tight = run(FakeExecutor(drifting(1, side=0.02)), clearance=lambda q: 0.01, reach=0.2)
    assert [e.outcome for e in tight.events][0] == "drift"
    assert tight.result.success


def test_drift_before_a_tight_push_replans_at_once() -> None:
    """The next push ends in a tight place (1 cm of clearance from x = 1.3 on): a 2 cm
    drift of the segment before it, in the open, already replans."""
    def clearance(q):
        return 0.01 if q[0] > 1.3 else 1.0

    out = run(FakeExecutor(drifting(1, side=0.02)), clearance=clearance, reach=0.2)
    assert [e.outcome for e in out.events][0] == "drift"  # at x = 1.2, before entering
    assert out.result.success


class SwervingExecutor(FakeExecutor):
    """Like ``FakeExecutor(exact)``, except that in segment 0 the object turns 0.3 rad half
    way: a watched push (``stop`` given) is stopped there, an unwatched one ends turned."""

    def __init__(self) -> None:
        super().__init__(exact)
        self.stops: list = []

    def execute(self, robot_paths, record_every=None, stop=None):
        self.stops.append(stop)
        if len(self.executed) > 0:
            return super().execute(robot_paths, record_every)
        paths = np.asarray(robot_paths, float)
        self.executed.append(paths)
        d = paths[0, -1] - paths[0, 0]
        self.poses[0, :2] += 0.5 * d
        self.poses[0, 2] += 0.3
        stopped = stop is not None and stop(self.poses.copy())
        if not stopped:
            self.poses[0, :2] += 0.5 * d
        self.robots = paths[:, paths.shape[1] // 2 if stopped else -1].copy()
        return SimpleNamespace(object_poses=self.poses.copy(), robot_positions=self.robots.copy(),
                               left_workspace=False, trace=None,
                               stopped_at=10 if stopped else None, declined=False)


def test_watch_stops_a_straight_push_in_a_tight_place_only() -> None:
    """A straight push through a tight place (1 cm of clearance) runs watched: the turn
    stops it half way, it is reported failed and the loop replans; in the open nothing is
    watched, and the turned object simply drifts."""
    open_ex = SwervingExecutor()
    open_run = run(open_ex, clearance=lambda q: 1.0, reach=0.2)
    assert all(s is None for s in open_ex.stops) and open_run.record.watch_stops == 0
    assert open_run.events[0].outcome == "drift"
    assert open_run.events[0].execution.object_poses[0, 0] == pytest.approx(1.2)
    assert all(f.q_from[0] > START[0] for f in open_run.planner.failures)
    tight_ex = SwervingExecutor()
    tight = run(tight_ex, clearance=lambda q: 0.01, reach=0.2)
    assert tight_ex.stops[0] is not None
    assert tight.events[0].outcome == "drift" and tight.record.watch_stops == 1
    assert tight.planner.failures[0].q_from[0] == pytest.approx(START[0])  # the push stopped
    assert all(f.q_from[0] > START[0] for f in tight.planner.failures[1:])  # (later: stalls)
    assert tight.events[0].execution.object_poses[0, 0] == pytest.approx(1.1)
