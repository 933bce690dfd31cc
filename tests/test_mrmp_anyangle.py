"""The assignment's descent over any-angle estimates (``lamp.mrmp.anyangle``): the walks
and pulled paths against plain references, the descent against the bottleneck over
every permutation, on random small maps; inside ``plan_paths``, the fleet checker and
small teams left as they were."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pytest
from fleet_plans import checked_plan, row_makespan
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import lamp.mrmp.anyangle as aa
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp import plan_paths
from lamp.mrmp.distance_field import get_lattice
from lamp.mrmp.goal_distances import GoalDistances, start_costs
from lamp.mrmp.gspi import warmup
from lamp.mrmp.links import Links, link_special_vertices
from lamp.scene.mapf import load_grid_map, random_instance
from lamp.scene.model import Obstacle, Rectangle, Scene

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05
STEP = 0.05


def _setup(seed: int, n: int, boxes: list) -> tuple | None:
    """A random 1.5 x 1.5 m map of rectangles, n robots with random free starts and
    goals at least 2r + 1 cm apart; its 5 cm lattice linked, every pair's lattice
    distance computed (so every goal's search settles the starts' links). None when
    some point has no link or no start reaches some goal."""
    obs = tuple(Obstacle(Rectangle((w, h)), (x, y, 0.0)) for x, y, w, h in boxes)
    sc = Scene("anyangle", (1.5, 1.5), ((0.1, 0.1),), (), obs)
    space = RobotSpace.from_scene(sc)
    rng = np.random.default_rng(seed)
    pts: list = []
    for _ in range(400):
        p = rng.uniform(0.1, 1.4, 2)
        if space.is_free(p[None], exact=True)[0] and all(
                np.hypot(*(p - q)) >= 2 * R + 0.01 for q in pts):
            pts.append(p)
        if len(pts) == 2 * n:
            break
    if len(pts) < 2 * n:
        return None
    S, G = np.array(pts[:n]), np.array(pts[n:])
    lat = get_lattice(space, STEP)
    c_s = space.clearance(S, exact=True)
    c_g = space.clearance(G, exact=True)
    links = link_special_vertices(space, lat, S, G, c_s, c_g, 1.5 * STEP, {})
    if not isinstance(links, Links):
        return None
    hs = GoalDistances.build(links.goal_links, G, lat, 2 * n)
    C = start_costs(0, n, n, links.graph, lat.V, hs)  # (N, M)
    if not np.isfinite(C).all():
        return None
    return space, S, G, links.graph, lat.V, hs, C


def _walk_length(pts: np.ndarray) -> float:
    return float(np.hypot(*np.diff(pts, axis=0).T).sum())


def _pulled_reference(pts: np.ndarray, space: RobotSpace) -> float:
    """Greedy string pulling, one exact segment check at a time: from each anchor, on
    while the segment to the next point keeps the threshold."""
    total, a = 0.0, 0
    while a < len(pts) - 1:
        j = a + 1
        while j + 1 < len(pts) and space.segment_free(pts[a][None], pts[j + 1][None])[0]:
            j += 1
        total += float(np.hypot(*(pts[j] - pts[a])))
        a = j
    return total


BOXES = st.lists(st.tuples(st.floats(0.2, 1.3), st.floats(0.2, 1.3), st.floats(0.05, 0.5),
                           st.floats(0.05, 0.5)), max_size=4)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(2, 4), boxes=BOXES)
def test_walks_follow_the_lattice_distance_and_pull_as_a_plain_reference(
        seed, n, boxes) -> None:
    """Every robot's walk to every goal runs from its start to the goal by graph edges
    and is as long as its lattice distance; pulled straight it is as long as a greedy
    reference with exact segment checks gives, between the straight line and the walk."""
    got = _setup(seed, n, boxes)
    assume(got is not None)
    space, S, G, gr, V, hs, C = got
    ob = aa.obstacles_of(space)
    buf = np.empty((400, 2))
    for i, m in itertools.product(range(n), range(n)):
        k = aa.lattice_walk(i, m, gr, V, V + n, hs, buf)
        assert k >= 2
        pts = buf[:k].copy()
        assert np.array_equal(pts[0], S[i]) and np.array_equal(pts[-1], G[m])
        assert np.hypot(*np.diff(pts, axis=0).T).max() <= 1.5 * STEP + 1e-9
        assert _walk_length(pts) == pytest.approx(C[i, m], abs=1e-5)
        pulled = aa.pull_straight(pts, k, ob)
        assert pulled == pytest.approx(_pulled_reference(pts, space), abs=1e-9)
        assert np.hypot(*(S[i] - G[m])) - 1e-9 <= pulled <= _walk_length(pts) + 1e-9
        assert aa.pulled_length(i, m, gr, V, V + n, hs, ob, buf) == pulled


def test_a_walk_in_the_open_pulls_to_the_straight_line() -> None:
    """Nothing in the way: the pulled walk is the straight line, shorter than the
    lattice distance when the line is off the lattice's eight directions."""
    got = _setup(3, 3, [])
    space, S, G, gr, V, hs, C = got
    buf = np.empty((400, 2))
    ob = aa.obstacles_of(space)
    for i in range(3):
        line = float(np.hypot(*(S[i] - G[i])))
        assert aa.pulled_length(i, i, gr, V, V + 3, hs, ob, buf) == pytest.approx(line,
                                                                                  abs=1e-12)
    assert (C.diagonal() > np.hypot(*(S - G).T) + 1e-3).any()


def _estimates(space, S, G, gr, V, hs, C) -> np.ndarray:
    """Every pair's estimate, from the module's definition: the pulled walk, never below
    the lattice distance over LIM."""
    n = len(S)
    ob = aa.obstacles_of(space)
    buf = np.empty((400, 2))
    return np.array([[max(aa.pulled_length(i, m, gr, V, V + n, hs, ob, buf), C[i, m] / aa.LIM)
                      for m in range(n)] for i in range(n)])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(2, 5), boxes=BOXES,
       start=st.randoms(use_true_random=False))
def test_the_descent_reaches_the_bottleneck_over_the_estimates(seed, n, boxes,
                                                               start) -> None:
    """From any assignment, the descent without a stop or a budget ends at the least,
    over every permutation, of the largest estimate; it returns a permutation with its
    pairs' lattice distances, and no larger estimate than it started with."""
    got = _setup(seed, n, boxes)
    assume(got is not None)
    space, S, G, gr, V, hs, C = got
    A = _estimates(space, S, G, gr, V, hs, C)
    best = min(max(A[i, p[i]] for i in range(n)) for p in itertools.permutations(range(n)))
    goal0 = np.array(start.sample(range(n), n), dtype=np.int64)
    cost0 = C[np.arange(n), goal0]
    goal, lat, _, _ = aa.descend(goal0, cost0, 0.0, gr, V, hs, S, G, space, 0.0, 10**4,
                                 10**6)
    assert sorted(goal.tolist()) == list(range(n))
    assert np.array_equal(lat, C[np.arange(n), goal])
    got_max = A[np.arange(n), goal].max()
    assert got_max <= A[np.arange(n), goal0].max() + 1e-12
    assert got_max == pytest.approx(best, abs=1e-12)
    # robots whose pairs were not in the way keep them when the start is already best
    if A[np.arange(n), goal0].max() <= best + 1e-12:
        assert np.array_equal(goal, goal0)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10**6), n=st.integers(2, 5), boxes=BOXES,
       stop=st.floats(0.0, 3.0), rounds=st.integers(0, 3), budget=st.integers(0, 4))
def test_the_descent_with_a_stop_and_a_budget_never_raises_the_largest_estimate(
        seed, n, boxes, stop, rounds, budget) -> None:
    """With any stop, round count and estimate budget: a permutation, the largest
    estimate no larger, at most ``rounds`` rounds, nothing changed once below the stop."""
    got = _setup(seed, n, boxes)
    assume(got is not None)
    space, S, G, gr, V, hs, C = got
    A = _estimates(space, S, G, gr, V, hs, C)
    goal0 = np.arange(n, dtype=np.int64)
    floor = 0.5
    goal, lat, done, _ = aa.descend(goal0, C.diagonal().copy(), floor, gr, V, hs, S, G,
                                    space, stop, rounds, budget)
    assert sorted(goal.tolist()) == list(range(n)) and done <= rounds
    assert A[np.arange(n), goal].max() <= A.diagonal().max() + 1e-12
    if C.diagonal().max() <= stop * floor or rounds == 0:
        assert np.array_equal(goal, goal0) and done == 0


def test_the_descent_inside_plan_paths_gives_a_checked_shorter_plan() -> None:
    """400 robots on random-64-64-20, seed 8, whose lattice bottleneck is 1.53 times the
    straight-line bound: the descent moves robots off their goals, the plan passes the
    fleet checker, every goal keeps one robot, a second call gives the same plan, and
    its makespan is below the one without the descent (1.58 m against 1.61 m)."""
    gm = load_grid_map(MAPF / "random-64-64-20.map", 0.15, R)
    S, G = random_instance(gm, 400, 8)
    plan = checked_plan(gm.scene, S, G, 8, R)
    assert plan.stats["descent_rounds"] >= 1
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(aa, "STOP", np.inf)
        plain = plan_paths(gm.scene, S, G, seed=8, time_limit=600.0)
    assert plain.success and plain.stats.get("descent_rounds", 0) == 0
    assert row_makespan(plan.paths) < row_makespan(plain.paths) - 0.01


def test_teams_of_up_to_100_robots_never_descend() -> None:
    """A team of 100 robots is planned without the descent (it is never called), so
    its plan is the one before it."""
    gm = load_grid_map(MAPF / "random-64-64-20.map", 0.15, R)
    S, G = random_instance(gm, aa.DESCEND_ABOVE, 3)

    def refuse(*args, **kwargs):
        raise AssertionError("descend called for a team of 100 robots")

    warmup()  # (which compiles the descent on two robots)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(aa, "descend", refuse)
        plan = plan_paths(gm.scene, S, G, seed=3, time_limit=600.0)
    assert plan.success and "descent_rounds" not in plan.stats
