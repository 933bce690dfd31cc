"""The timed repair's group and exchange rounds (``lamp.mrmp.timed_repair``,
``timed_checks.motion_hits`` and ``rest_clear``): the robots named as in the way against
a brute-force reference, robot by robot; and fleets whose last robots are planned again
with the robots in their way or exchange goals with them, every plan checked by the
independent fleet checker, the exchanged goals a permutation of the given ones, the last
arrival never later, the plan the same on a second call."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from hypothesis import given, settings
from hypothesis import strategies as st
from test_mrmp_timed_repair import _blocked_by, _makespan, _pair_ok, _random_rows

import lamp.mrmp.gspi as gspi
from lamp.mrmp import plan_paths
from lamp.mrmp.repair_hash import hash_rows
from lamp.mrmp.timed_checks import arrivals, motion_hits, rest_clear
from lamp.mrmp.timed_repair import _near_holders, timed_budget
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05
SPACING = 0.02
CS = 2 * R + 0.04 + 2 * SPACING + 1e-6


def _move(rng, tt):
    a = rng.uniform(0.1, 0.6, 2)
    b = a + (rng.uniform(-0.04, 0.04, 2) if rng.random() < 0.8 else 0.0)
    t0 = float(rng.uniform(-0.01, tt[-1] + 0.02))
    return a, b, t0, t0 + float(rng.uniform(0.005, 0.08))


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 8), rows=st.integers(2, 12),
       as_way=st.booleans())
def test_motion_hits_names_exactly_the_robots_in_the_way(seed, n, rows, as_way) -> None:
    """Random rows and a random move (or wait) of robot 0: the robots marked are exactly
    those the reference finds too close, one by one; with robot 1's rows given as its new
    way instead, the same."""
    rng = np.random.default_rng(seed)
    X, Y, tt = _random_rows(rng, n, rows)
    a, b, t0, t1 = _move(rng, tt)
    hh, ny = hash_rows(X, Y, -0.5, -0.5, 1.5, 1.5, CS, True)
    rep = np.zeros(n, np.bool_)
    ways = (rep, np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1, np.int64),
            np.zeros(0, np.int64), np.zeros((0, 4)))
    if as_way:
        rep[1] = True
        ways = (rep, X[:, 1].copy(), Y[:, 1].copy(), tt.copy(),
                np.array([0, rows], np.int64), np.array([1], np.int64),
                np.array([[X[:, 1].min(), X[:, 1].max(), Y[:, 1].min(), Y[:, 1].max()]]))
    hit = np.zeros(n, np.bool_)
    motion_hits(0, a[0], a[1], b[0], b[1], t0, t1, False, X, Y, tt, hh, -0.5, -0.5, CS, ny,
                2 * R, np.zeros(n, np.bool_), ways, hit)
    want = [k for k in range(1, n) if _blocked_by(k, a, b, t0, t1, X, Y, tt)]
    assert np.flatnonzero(hit).tolist() == want


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 8), rows=st.integers(2, 12))
def test_rest_clear_matches_a_reference(seed, n, rows) -> None:
    """Random rows and a random move of robot 0: it is clear of the others' last positions
    from their arrivals on exactly when the reference says so (each piece from
    ``max(t0, arrival)`` to ``t1`` against the still robot)."""
    rng = np.random.default_rng(seed)
    X, Y, tt = _random_rows(rng, n, rows)
    a, b, t0, t1 = _move(rng, tt)
    hh, ny = hash_rows(X, Y, -0.5, -0.5, 1.5, 1.5, CS, True)
    arr = arrivals(X, Y, tt)
    got = rest_clear(0, a[0], a[1], b[0], b[1], t0, t1, X, Y, hh, -0.5, -0.5, CS, ny, 2 * R,
                     arr)
    want = True
    for k in range(1, n):
        if arr[k] >= t1:
            continue
        s0 = max(t0, arr[k])
        p0 = a + (b - a) * (s0 - t0) / (t1 - t0)
        last = np.array([X[-1, k], Y[-1, k]])
        want &= _pair_ok(p0, b, last, last)
    assert got == want


def test_timed_budget_grows_with_the_square_of_the_fleet() -> None:
    assert timed_budget(100) == timed_budget(400) == 5000
    assert timed_budget(800) == 20_000
    assert timed_budget(1600) == 40_000


@pytest.mark.parametrize(("seed", "exchange"), [(2, True), (5, True)])
def test_groups_and_exchanges_inside_plan_paths(seed: int, exchange: bool) -> None:
    """800 robots on ``random-64-64-20`` (seed 2: group rounds, one restarted, and an
    exchange; seed 5: goal exchanges, with a robot in the way and with the holder of a
    goal near the last robot's start), the stage spied on: it planned robots together, the goals it returns are
    a permutation of those it was given and the plan's own, the fleet checker accepts the
    plan (the general one takes minutes at this size), the last arrival is no later than
    the retiming's, and a second call gives the same plan."""
    gm = load_grid_map(MAPF / "random-64-64-20.map")
    S, G = random_instance(gm, 800, seed)
    seen = {}
    real = gspi.timed_repair

    def spy(rows, times, gr, V, gv0, hs, goal, *args, **kw):
        out = real(rows, times, gr, V, gv0, hs, goal, *args, **kw)
        seen.update(before=_makespan(rows), given=np.array(goal), out=out)
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_repair", spy)
        plan = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert plan.success and seen
    _, goal, done, _, groups = seen["out"]
    assert groups >= 1 and done >= 2
    assert ((goal != seen["given"]).sum() >= 2) == exchange  # exchanges may chain
    assert np.array_equal(np.sort(goal), np.sort(seen["given"]))
    assert np.array_equal(plan.goal_of, goal)
    assert _makespan(plan.paths) <= seen["before"] + 1e-6
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []
    again = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert np.array_equal(again.paths, plan.paths)
    assert np.array_equal(again.goal_of, plan.goal_of)


def test_group_restarts_inside_plan_paths() -> None:
    """800 robots on ``random-64-64-20``, seed 13: a group whose member planned after the
    last robot finds no way is planned again with that member first. The stage's input
    repaired with and without restarts: both arrive no later than the retiming, the
    restarts strictly earlier (1.14 m against 1.47 m), with more ways planned; the fleet
    checker accepts the plan with them, and a second call gives the same rows."""
    gm = load_grid_map(MAPF / "random-64-64-20.map")
    S, G = random_instance(gm, 800, 13)
    seen = {}
    real = gspi.timed_repair

    def spy(*args, **kw):
        seen.update(args=args, kw=kw)
        return real(*args, **kw)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_repair", spy)
        plan = plan_paths(gm.scene, S, G, seed=13, time_limit=600.0)
    assert plan.success and seen
    before = _makespan(seen["args"][0])
    none = real(*seen["args"], **seen["kw"], restarts=0)
    again = real(*seen["args"], **seen["kw"])
    assert np.array_equal(again[0], plan.paths)
    assert again[2] > none[2]
    assert _makespan(none[0]) <= before + 1e-6
    assert _makespan(plan.paths) < _makespan(none[0]) - 0.1
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []


def test_exchange_when_no_way_even_alone() -> None:
    """800 robots on ``random-64-64-20``, seed 47: the goal of the robot that arrives
    last is farther, on the lattice, than any way before the last arrival, even with no
    other robot about; it exchanges goals with the holder of a goal near its start
    (before: the stage stopped there, at 1.19 m), the last arrival at most 1.0 m, the
    goals a permutation of those given, and the fleet checker accepts the plan."""
    gm = load_grid_map(MAPF / "random-64-64-20.map")
    S, G = random_instance(gm, 800, 47)
    seen = {}
    real = gspi.timed_repair

    def spy(rows, times, gr, V, gv0, hs, goal, *args, **kw):
        out = real(rows, times, gr, V, gv0, hs, goal, *args, **kw)
        X, Y = np.ascontiguousarray(rows[:, :, 0].T), np.ascontiguousarray(rows[:, :, 1].T)
        last = int(np.argmax(arrivals(X, Y, np.asarray(times, np.float64))))
        seen.update(before=_makespan(rows), given=np.array(goal), out=out, last=last)
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_repair", spy)
        plan = plan_paths(gm.scene, S, G, seed=47, time_limit=600.0)
    assert plan.success and seen
    goal = seen["out"][1]
    assert seen["before"] > 1.19 and _makespan(plan.paths) <= 1.0
    assert goal[seen["last"]] != seen["given"][seen["last"]]
    assert np.array_equal(np.sort(goal), np.sort(seen["given"]))
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []


@settings(max_examples=200, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 30), k=st.integers(0, 6),
       limit=st.floats(0.05, 1.5))
def test_near_holders_matches_a_reference(seed, n, k, limit) -> None:
    """The exchange partners offered to the last robot (after those in its way): robots
    not tried, holding a goal, whose goal lies within ``limit`` of its start and whose
    start within ``limit`` of its goal, the longer line shortest first, ties by index,
    at most ``k``; against a plain sort over every robot."""
    rng = np.random.default_rng(seed)
    M = n + int(rng.integers(0, 3))  # goals, some held by nobody
    V = 5
    coords = np.round(rng.random((V + n + M, 2)), 1)  # rounded: ties happen
    goal = np.full(n, -1, np.int64)
    held = rng.permutation(M)[:n]
    has = rng.random(n) < 0.85
    goal[has] = held[has]
    i = int(rng.integers(n))
    if goal[i] < 0:
        goal[i] = held[i]
    tried = rng.random(n) < 0.2
    gv0 = V + n
    got = _near_holders(i, goal, coords, V, gv0, limit, tried, k)
    s, g = coords[V + i], coords[gv0 + goal[i]]
    want = []
    for j in range(n):
        if j == i or goal[j] < 0 or tried[j]:
            continue
        m = max(np.hypot(*(coords[gv0 + goal[j]] - s)), np.hypot(*(coords[V + j] - g)))
        if m < limit:
            want.append((m, j))
    assert got.tolist() == [j for _, j in sorted(want)[:k]]
