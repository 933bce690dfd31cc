"""The Verifier behind its narrow protocols: an open plane or a walled-off world as the
robots' free space, a straight-line multi-robot planner, the geometric model.

No scene and no Gspi: what is checked is what ``Verifier`` itself guarantees (the
proposal cache and counters, ``Collide`` through ``RobotValidity``, the transition it
builds, GCo's uncached single sample, the window growth of ``approach``).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from lamp.contract.trajectory import MAX_STEP, straight_moves
from lamp.geometry import se2
from lamp.manip import GeometricProposer
from lamp.mrmp.gspi import GspiStatus
from lamp.planners.config import VerifyConfig
from lamp.planners.verifier import Verifier
from lamp.scene.model import Rectangle

SHAPE = Rectangle((0.4, 0.3))
R = GeometricProposer.robot_radius
Q_FROM = np.array([2.0, 2.0, 0.3])
ROBOTS = np.array([[1.2, 1.5], [1.3, 2.8], [2.8, 1.2]])


class Plane:
    """A free space where ``free(points)`` says what is free; windows of fixed size."""

    max_window_side = 16.0

    def __init__(self, free=lambda p: np.ones(len(p), bool), covers: bool = True) -> None:
        self.free = free
        self.covers = covers
        self.asked: list[tuple] = []

    def window(self, q_object, points=None, scale=1.0):
        return (0.0, 0.0, 4.0 * scale, 4.0 * scale)

    def robot_space_at(self, q_object, window=None):
        self.asked.append(("at", tuple(np.round(q_object, 6)), window))
        return self._space()

    def static_space_near(self, q_object):
        self.asked.append(("static", tuple(np.round(q_object, 6)), None))
        return self._space()

    def _space(self):
        free = self.free
        return SimpleNamespace(
            covers_workspace=self.covers,
            is_free=lambda p: free(np.asarray(p, float).reshape(-1, 2)),
            segment_free=lambda a, b: free(np.asarray(a, float)) & free(np.asarray(b, float)),
            nearest_free=lambda p, accept=None, max_distance=None: np.asarray(p, float))


class StraightRouter:
    """Robots go straight to their optimally assigned goals (``fail`` statuses first)."""

    def __init__(self, fail: tuple = ()) -> None:
        self.fail = list(fail)
        self.calls: list[np.ndarray] = []

    def __call__(self, q_object, starts, goals, space, time_limit):
        self.calls.append(np.array(goals))
        if self.fail:
            return SimpleNamespace(success=False, status=self.fail.pop(0))
        cost = np.linalg.norm(starts[:, None] - goals[None], axis=2)
        rows, cols = linear_sum_assignment(cost)
        goal_of = np.empty(len(starts), int)
        goal_of[rows] = cols
        return SimpleNamespace(success=True, status=GspiStatus.SOLVED, goal_of=goal_of,
                               paths=straight_moves(starts, goals[goal_of]))


def make(robots=None, router=None, **params) -> Verifier:
    return Verifier(GeometricProposer(), SHAPE, R, len(ROBOTS), robots or Plane(),
                    router or StraightRouter(), VerifyConfig(**params), seed=3)


def test_verify_builds_the_transition_and_counts() -> None:
    v = make()
    q_to = se2.compose(Q_FROM, np.array([0.15, 0.0, 0.1]))
    trans = v.verify(Q_FROM, q_to, ROBOTS)
    assert trans is not None and trans.budget == 3  # budgets from min(N, max_budget) down
    assert np.allclose(trans.robot_start, ROBOTS)
    assert np.allclose(trans.contacts, se2.transform_points(Q_FROM, trans.pushes_local[:, 0]))
    # the pushers end where their pushes end; every step of T_R is executable
    ends = se2.transform_points(Q_FROM, trans.pushes_local[:, -1])
    assert np.allclose(np.sort(trans.robot_end, axis=0), np.sort(ends, axis=0))
    assert np.all(np.linalg.norm(np.diff(trans.robot_paths, axis=1), axis=2) <= MAX_STEP + 1e-9)
    s = v.stats
    assert (s.verify_calls, s.verify_success, s.model_calls, s.gspi_calls, s.gspi_success) == \
        (1, 1, 1, 1, 1)


@settings(max_examples=20, deadline=None)
@given(motion=st.tuples(st.integers(-200, 200), st.integers(-200, 200), st.integers(-300, 300)),
       attempts=st.lists(st.integers(0, 2), min_size=1, max_size=6))
def test_proposals_are_cached_per_motion_budget_and_attempt(motion, attempts) -> None:
    """One model call per distinct (motion, budget, attempt), a cache hit for every
    repeat, and a repeat returns the very same proposals."""
    v = make()
    first = {}
    for a in attempts:
        props = v.proposals.get(np.array(motion) / 1000.0, 2, a)  # mm and mrad
        assert first.setdefault(a, props) is props
    assert v.stats.model_calls == len(set(attempts))
    assert v.stats.cache_hits == len(attempts) - len(set(attempts))


def test_sample_is_one_uncached_draw() -> None:
    v = make()
    a = v.proposals.sample(np.array([0.1, 0.0, 0.0]), 3, seed=5)
    b = v.proposals.sample(np.array([0.1, 0.0, 0.0]), 3, seed=5)
    assert a.shape[0] == 3 and np.array_equal(a, b)  # deterministic for a seed
    assert v.stats.model_calls == 2 and v.stats.cache_hits == 0


def test_collide_goes_through_the_robot_validity() -> None:
    # nothing is free: Collide drops every proposal, the router is never asked
    router = StraightRouter()
    robots = Plane(free=lambda p: np.zeros(len(p), bool))
    v = make(robots=robots, router=router)
    assert v.verify(Q_FROM, se2.compose(Q_FROM, np.array([0.1, 0.0, 0.0])), ROBOTS) is None
    assert router.calls == [] and v.stats.verify_success == 0
    assert {kind for kind, _, _ in robots.asked} == {"static"}
    assert v.stats.model_calls == 3  # budgets 3, 2, 1


def test_approach_widens_the_window_on_a_window_bound_failure() -> None:
    robots = Plane(covers=False)
    router = StraightRouter(fail=(GspiStatus.UNREACHABLE, GspiStatus.STALLED))
    v = make(robots=robots, router=router)
    goals = ROBOTS + 0.1
    routed = v.approach(Q_FROM, ROBOTS, goals)
    assert routed is not None and len(router.calls) == 3
    windows = [w for kind, _, w in robots.asked if kind == "at"][1:]  # after leave_contact
    assert [w[2] for w in windows] == [4.0, 8.0, 16.0]
    # a failure a larger window cannot fix ends the approach at once
    router = StraightRouter(fail=(GspiStatus.INVALID_GOAL,))
    v = make(robots=Plane(covers=False), router=router)
    assert v.approach(Q_FROM, ROBOTS, goals) is None and len(router.calls) == 1
    assert v.stats.gspi_calls == 1 and v.stats.gspi_success == 0


def test_a_robot_routed_from_beyond_the_objects_window_is_backed_off_first() -> None:
    """A robot outside the object's own window (``leave_contact`` does not look there)
    but inside the routing window stands a few mm inside a body: ``approach`` backs it
    off to the nearest free spot of the routing space before Gspi is asked (which refuses
    a start that is not free), and the path starts where the robot stands."""
    stuck_at, spot = np.array([5.0, 1.0]), np.array([5.03, 1.0])

    class Wide(Plane):
        def window(self, q_object, points=None, scale=1.0):
            side = 4.0 if points is None else 8.0 * scale  # the object's own: 4 m
            return (0.0, 0.0, side, side)

        def _space(self):
            space = super()._space()
            space.nearest_free = lambda p, accept=None, max_distance=None: (
                spot.copy() if np.allclose(p, stuck_at) else np.asarray(p, float))
            return space

    def free(p):
        return np.linalg.norm(p - stuck_at, axis=1) > 0.01

    class Refusing(StraightRouter):
        def __call__(self, q_object, starts, goals, space, time_limit):
            if not space.is_free(starts).all():
                return SimpleNamespace(success=False, status=GspiStatus.INVALID_START)
            return super().__call__(q_object, starts, goals, space, time_limit)

    robots = np.array([[1.2, 1.5], [1.3, 2.8], stuck_at])
    v = make(robots=Wide(free=free), router=Refusing())
    routed = v.approach(Q_FROM, robots, robots + [0.0, 0.1])
    assert routed is not None
    paths, _ = routed
    assert np.allclose(paths[:, 0], robots, atol=MAX_STEP)
    assert np.any(np.linalg.norm(paths[2] - spot, axis=1) < 1e-9)  # it passed the spot
    assert np.all(np.linalg.norm(np.diff(paths, axis=1), axis=2) <= MAX_STEP + 1e-9)


def test_params_are_validated() -> None:
    for bad in ({"k": 0}, {"max_budget": 1.5}, {"gspi_time_limit": 0.0},
                {"contact_tolerance": -1.0}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            VerifyConfig(**bad)


def _wedged_box_task():
    """A 0.4 x 0.2 m box in a corridor 2 cm wider, every robot on its left."""
    from lamp.planners.config import PlannerConfig
    from lamp.planners.task import ManipulationTask
    from lamp.scene.loader import scene_from_dict

    scene = scene_from_dict({
        "format": "lamp-scene/1", "name": "wedged", "workspace": [3.0, 1.0],
        "robots": {"radius": 0.05, "starts": [[0.9, 0.44], [0.9, 0.56], [0.7, 0.5]]},
        "obstacles": [{"type": "rectangle", "center": [1.5, 0.195], "size": [3.0, 0.39]},
                      {"type": "rectangle", "center": [1.5, 0.805], "size": [3.0, 0.39]}],
        "objects": [{"type": "rectangle", "size": [0.4, 0.2], "start": [1.5, 0.5, 0.0],
                     "goal": [2.5, 0.5, 0.0]}]})
    task = ManipulationTask(scene, 0, np.array([[1.5, 0.5, 0.0]]), GeometricProposer(),
                            PlannerConfig(), seed=0)
    return task, np.array(scene.robot_starts, float)


def test_contacts_beyond_a_wedged_object_are_unreachable():
    task, robots = _wedged_box_task()
    v = task.verifier
    q = np.array([1.5, 0.5, 0.0])
    forward, back = np.array([1.6, 0.5, 0.0]), np.array([1.4, 0.5, 0.0])
    assert v.can_reach(q, forward, robots)
    assert not v.can_reach(q, back, robots)  # pushed from the right, where no robot is
    assert v.stats.gspi_calls == 0  # a test without Gspi
    unreachable = v._unreachable(q, robots)
    back_props = v._usable_proposals(q, robots, se2.relative(q, back), 1, 0)
    assert back_props and all(unreachable(p) for p in back_props)
    fwd_props = v._usable_proposals(q, robots, se2.relative(q, forward), 1, 0)
    assert any(not unreachable(p) for p in fwd_props)
    assert v.verify(q, forward, robots) is not None
    calls = v.stats.gspi_calls
    assert v.verify(q, back, robots) is None
    assert v.stats.gspi_calls > calls  # still tried: a wider window might reach round


def test_after_a_failed_approach_reachable_contacts_go_first():
    """The nearest candidate is tried first; once an approach fails, the rest are tried
    reachable first (nearest first within each group)."""
    task, robots = _wedged_box_task()
    v = task.verifier
    q = np.array([1.5, 0.5, 0.0])
    def push(x: float) -> np.ndarray:  # one robot's push path (object frame), from x
        return np.array([[[x, 0.0], [x + 0.01, 0.0]]])

    beyond, behind = 0.26, -0.26  # right of the box (no robot there) and left of it
    order = [push(beyond), push(beyond), push(behind), push(behind)]  # "nearest" first
    tried = []
    v._usable_proposals = lambda *a, **k: [p.copy() for p in order]
    v.route_push = lambda q_from, q_to, q_R, pushes: tried.append(pushes[0, 0, 0]) or None
    assert v.verify(q, np.array([1.6, 0.5, 0.0]), robots) is None
    assert tried[:3] == [beyond, behind, behind]
