"""The sparse least-sum assignment (lamp.mrmp.sparse_lsa) against scipy's dense one, and
the fleet assignment that uses it against the exact objective."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.optimize import linear_sum_assignment

from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.assignment import assign
from lamp.mrmp.distance_field import get_lattice
from lamp.mrmp.goal_distances import GoalDistances, start_costs
from lamp.mrmp.links import link_special_vertices
from lamp.mrmp.sparse_lsa import sparse_assignment
from lamp.scene.mapf import load_grid_map, random_instance


@settings(max_examples=200)
@given(st.integers(0, 2**31 - 1), st.integers(1, 40), st.integers(0, 8),
       st.floats(0.02, 1.0), st.integers(0, 4))
def test_least_sum_over_sparse_pairs(seed: int, M: int, extra: int, density: float,
                                     digits: int) -> None:
    rng = np.random.default_rng(seed)
    N = M + extra
    # rounded costs: many ties, as lattice distances have
    C = rng.uniform(0.0, 3.0, (M, N)).round(digits)
    mask = rng.random((M, N)) < density
    pm, pi = np.nonzero(mask)
    got = sparse_assignment(np.searchsorted(pm, np.arange(M + 1)), pi, C[pm, pi], N)
    W = np.where(mask, C, 1e9)
    rows, cols = linear_sum_assignment(W)
    feasible = bool((W[rows, cols] < 1e9).all())
    if not feasible:
        assert got is None
        return
    assert got is not None
    assert len(np.unique(got)) == M  # every goal its own robot
    assert mask[np.arange(M), got].all()  # allowed pairs only
    assert abs(C[np.arange(M), got].sum() - W[rows, cols].sum()) <= 1e-9 * max(1, M)


def test_no_goals_and_no_pairs() -> None:
    assert len(sparse_assignment(np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0), 3)) == 0
    assert sparse_assignment(np.zeros(2, np.int64), np.zeros(0, np.int64), np.zeros(0), 3) is None
    # two goals that only one robot can serve
    assert sparse_assignment(np.array([0, 1, 2]), np.array([0, 0]), np.array([1.0, 2.0]), 2) is None


MAPF = Path(__file__).resolve().parent / "data" / "mapf"


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(32, 60), extra=st.integers(0, 6))
def test_fleet_assignment_is_bottleneck_then_least_sum(seed: int, n: int, extra: int) -> None:
    """A fleet's assignment (wide first windows, the sparse least sum with its tie-break
    by squares): the least longest exact distance, and the least sum among those to
    within the tie-break's 1e-6 of the summed squares; checked on the whole cost matrix."""
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n + extra, seed)
    G = G[:n]
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    N, M = len(S), len(G)
    links = link_special_vertices(space, lat, S, G, space.clearance(S, exact=True),
                                  space.clearance(G, exact=True), 0.045, {})
    hs = GoalDistances.build(links.goal_links, G, lat, N + M)
    got = assign(links.graph, lat.V, hs, S, G, np.zeros(M, bool), "bottleneck", None, np.inf)
    ref = GoalDistances.build(links.goal_links, G, lat, N + M)
    C = start_costs(0, M, N, links.graph, lat.V, ref)  # (N, M)
    vals = np.unique(C[np.isfinite(C)])
    lo, hi = 0, len(vals) - 1  # least threshold with a full matching of the goals
    while lo < hi:
        mid = (lo + hi) // 2
        r, c = linear_sum_assignment(vals[mid] < C.T)
        lo, hi = (lo, mid) if not (C.T[r, c] > vals[mid]).any() else (mid + 1, hi)
    bstar = vals[lo]
    W = np.where(bstar >= C.T, C.T, 1e9)
    r, c = linear_sum_assignment(W)
    assert got.goal is not None
    held = np.flatnonzero(got.goal >= 0)
    assert sorted(got.goal[held].tolist()) == list(range(M))
    cost = C[held, got.goal[held]]
    assert np.array_equal(cost, got.cost[held])
    assert cost.max() == bstar and got.bound == bstar
    assert W[r, c].sum() - 1e-9 <= cost.sum() <= W[r, c].sum() + 1e-6 * (cost**2).sum() + 1e-9


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(32, 60), growth=st.floats(1.01, 1.3),
       ahead=st.integers(0, 6), later=st.integers(0, 3), room=st.floats(1.0, 1.6))
# searches far ahead complete (the whole lattice) for goals no robot reaches below the
# bound yet: they are not unreachable
@example(seed=0, n=32, growth=1.25, ahead=6, later=0, room=1.0)
def test_fleet_assignment_does_not_depend_on_its_rounds(seed: int, n: int, growth: float,
                                                        ahead: int, later: int,
                                                        room: float) -> None:
    """The rounds of a fleet's assignment (the bound's growth, how far the first search
    reaches ahead, the windows' room) change only how far the goals' searches go: any
    schedule gives the default's assignment, costs and ``B*``, bit for bit."""
    from unittest import mock

    from lamp.mrmp import assignment

    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, seed)
    space = RobotSpace.from_scene(gm.scene)
    lat = get_lattice(space, 0.03)
    N, M = len(S), len(G)
    links = link_special_vertices(space, lat, S, G, space.clearance(S, exact=True),
                                  space.clearance(G, exact=True), 0.045, {})
    got = []
    for rounds in (assignment.FLEET_ROUNDS, (growth, ahead, later, room)):
        hs = GoalDistances.build(links.goal_links, G, lat, N + M)
        with mock.patch.object(assignment, "FLEET_ROUNDS", rounds):
            got.append(assign(links.graph, lat.V, hs, S, G, np.zeros(M, bool), "bottleneck",
                              None, np.inf))
    a, b = got
    assert a.goal is not None and b.goal is not None
    assert np.array_equal(a.goal, b.goal) and np.array_equal(a.cost, b.cost)
    assert a.bound == b.bound
