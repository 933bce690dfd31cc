"""Timed repair of retimed fleet plans (``lamp.mrmp.timed_repair``, ``timed_checks``):
its motion check against a brute-force reference over every piece of time, the rows it
writes, and inside ``plan_paths`` (both independent checkers, the last arrival never
later)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from hypothesis import given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan

import lamp.mrmp.gspi as gspi
from lamp.mrmp import plan_paths
from lamp.mrmp.repair_hash import hash_rows
from lamp.mrmp.timed_checks import (
    arrivals,
    gather_rows,
    motion_clear,
    motion_near,
    row_at,
    with_way,
)
from lamp.scene.mapf import load_grid_map, random_instance

MAPF = Path(__file__).resolve().parent / "data" / "mapf"
R = 0.05
SPACING = 0.02


def _way_of_robot_1(X, Y, tt):
    """The ways table of ``timed_checks`` with robot 1's rows as its one repaired way."""
    rows, n = X.shape
    rep = np.zeros(n, np.bool_)
    rep[1] = True
    return (rep, X[:, 1].copy(), Y[:, 1].copy(), tt.copy(),
            np.array([0, rows], np.int64), np.array([1], np.int64),
            np.array([[X[:, 1].min(), X[:, 1].max(), Y[:, 1].min(), Y[:, 1].max()]]))


def _pair_ok(a, b, c, d, two_r=2 * R) -> bool:
    """Two robots moving a->b and c->d over the same span: their closest approach (closed
    form) is at least ``min(2r, distance at the span's start)``."""
    p, q = np.subtract(a, c), np.subtract(b, d)
    u = q - p
    den = float(u @ u)
    s = 0.0 if den == 0.0 else min(1.0, max(0.0, -float(p @ u) / den))
    return float(np.hypot(*(p + s * u))) >= min(two_r, float(np.hypot(*p))) - 1e-9


def _pos(X, Y, tt, k, t):
    """Robot k's position at time t in the rows (np.interp: linear, still outside)."""
    return np.array([np.interp(t, tt, X[:, k]), np.interp(t, tt, Y[:, k])])


def _blocked_by(k, a, b, t0, t1, X, Y, tt) -> bool:
    """Whether the move a -> b over [t0, t1] comes closer to robot k's rows than the rule
    allows, cut at every row time inside (no goal ends)."""
    cuts = np.unique(np.concatenate([[t0, t1], tt[(tt > t0) & (tt < t1)]]))
    for s0, s1 in zip(cuts[:-1], cuts[1:], strict=True):
        p0 = a + (b - a) * (s0 - t0) / (t1 - t0)
        p1 = a + (b - a) * (s1 - t0) / (t1 - t0)
        if not _pair_ok(p0, p1, _pos(X, Y, tt, k, s0), _pos(X, Y, tt, k, s1)):
            return True
    return False


def _reference(i, a, b, t0, t1, X, Y, tt) -> bool:
    """Robot i moving a -> b over [t0, t1] against every other robot's rows, cut at every
    row time inside (no goal ends)."""
    return not any(_blocked_by(k, a, b, t0, t1, X, Y, tt)
                   for k in range(X.shape[1]) if k != i)


def _random_rows(rng, n, rows, box=0.6):
    """Rows of n robots moving at most SPACING per row, at increasing times that last at
    most SPACING each."""
    X = np.empty((rows, n))
    Y = np.empty((rows, n))
    X[0], Y[0] = rng.uniform(0.1, box, n), rng.uniform(0.1, box, n)
    for r in range(1, rows):
        step = rng.uniform(-1, 1, (2, n)) * SPACING / 1.5 * rng.integers(0, 2, n)
        X[r], Y[r] = X[r - 1] + step[0], Y[r - 1] + step[1]
    tt = np.concatenate([[0.0], np.cumsum(rng.uniform(0.3, 1.0, rows - 1) * SPACING)])
    return X, Y, tt


def _no_ways(n):
    return (np.zeros(n, np.bool_), np.zeros(1), np.zeros(1), np.zeros(1),
            np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros((0, 4)))


@settings(max_examples=400, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 7), rows=st.integers(2, 12),
       as_way=st.booleans())
def test_motion_clear_matches_a_brute_force_reference(seed, n, rows, as_way) -> None:
    """Random rows and a random move (or wait) of robot 0 over a random span: the hashed,
    piecewise check agrees with the reference; with another robot's rows given as its new
    way instead, the answer is the same."""
    rng = np.random.default_rng(seed)
    X, Y, tt = _random_rows(rng, n, rows)
    a = rng.uniform(0.1, 0.6, 2)
    b = a + (rng.uniform(-0.04, 0.04, 2) if rng.random() < 0.8 else 0.0)
    t0 = float(rng.uniform(-0.01, tt[-1] + 0.02))
    t1 = t0 + float(rng.uniform(0.005, 0.08))
    cs = 2 * R + 0.04 + 2 * SPACING + 1e-6
    hh, ny = hash_rows(X, Y, -0.5, -0.5, 1.5, 1.5, cs, True)
    ends = np.zeros(n, np.bool_)
    ways = _no_ways(n)
    if as_way:  # robot 1 follows its rows as a "new way"
        rep = np.zeros(n, np.bool_)
        rep[1] = True
        ways = (rep, X[:, 1].copy(), Y[:, 1].copy(), tt.copy(),
                np.array([0, rows], np.int64), np.array([1], np.int64),
                np.array([[X[:, 1].min(), X[:, 1].max(), Y[:, 1].min(), Y[:, 1].max()]]))
    got = motion_clear(0, a[0], a[1], b[0], b[1], t0, t1, False, X, Y, tt, hh, -0.5, -0.5,
                       cs, ny, 2 * R, ends, ways)
    assert got == _reference(0, a, b, t0, t1, X, Y, tt)


@settings(max_examples=400, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 14), rows=st.integers(2, 14),
       as_way=st.booleans(), split=st.integers(0, 3))
def test_motion_near_gives_motion_clears_answers(seed, n, rows, as_way, split) -> None:
    """The timed search's check of a move against the robots gathered around its start
    (``gather_rows``, ``motion_near``) gives ``motion_clear``'s answer over the hash, and
    the brute-force reference's without goal ends: random crowded rows, moves no longer
    than the hash's longest (waits too), random goal ends, another robot's rows as its
    new way, the rows gathered at once or in parts (as successive moves need them)."""
    rng = np.random.default_rng(seed)
    X, Y, tt = _random_rows(rng, n, rows, box=0.35)
    longest = 0.04
    a = rng.uniform(0.1, 0.35, 2)
    ang = rng.uniform(0, 2 * np.pi)
    b = a + (rng.uniform(0, longest) * np.array([np.cos(ang), np.sin(ang)])
             if rng.random() < 0.8 else 0.0)
    t0 = float(rng.uniform(-0.01, tt[-1] + 0.02))
    t1 = t0 + float(rng.uniform(0.005, 0.08))
    cs = 2 * R + longest + 2 * SPACING + 1e-6
    hh, ny = hash_rows(X, Y, -0.5, -0.5, 1.5, 1.5, cs, True)
    goal_ends = rng.random() < 0.5
    ends = rng.random(n) < 0.5 if goal_ends else np.zeros(n, np.bool_)
    end_goal = goal_ends and bool(rng.random() < 0.5)
    ways = _way_of_robot_1(X, Y, tt) if as_way else _no_ways(n)
    r0, r_end = row_at(tt, t0), row_at(tt, t1)
    gk = np.empty(1, np.int64)
    gptr = np.zeros(rows + 1, np.int64)
    nrows = 0
    for stop in sorted({min(r_end, r0 + split), r_end}):
        gk, nrows = gather_rows(0, a[0], a[1], r0, nrows, stop, hh, -0.5, -0.5, cs, ny,
                                ways[0], gk, gptr)
    assert nrows == r_end - r0 + 1
    got = motion_near(0, a[0], a[1], b[0], b[1], t0, t1, end_goal, X, Y, tt, 2 * R, ends,
                      ways, gk, gptr, r0)
    want = motion_clear(0, a[0], a[1], b[0], b[1], t0, t1, end_goal, X, Y, tt, hh, -0.5,
                        -0.5, cs, ny, 2 * R, ends, ways)
    assert got == want
    if not goal_ends:
        assert got == _reference(0, a, b, t0, t1, X, Y, tt)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 6), rows=st.integers(2, 10))
def test_with_way_keeps_the_others_and_writes_the_way(seed, n, rows) -> None:
    """Writing robot 0's new way: every other robot is where it was at every old row
    time and in between (exact interpolation), robot 0 is at each way point at its time,
    and no robot moves more than the spacing between two rows."""
    rng = np.random.default_rng(seed)
    X, Y, tt = _random_rows(rng, n, rows)
    k = int(rng.integers(2, 6))
    wt = np.concatenate([[0.0], np.cumsum(rng.uniform(0.01, 0.05, k - 1))])
    wx = np.concatenate([[X[0, 0]], X[0, 0] + np.cumsum(rng.uniform(-0.03, 0.03, k - 1))])
    wy = np.concatenate([[Y[0, 0]], Y[0, 0] + np.cumsum(rng.uniform(-0.03, 0.03, k - 1))])
    NX, NY, nt = with_way(X, Y, tt, 0, wx, wy, wt, SPACING)
    assert np.all(np.diff(nt) > 0)
    for s in np.concatenate([tt, nt]):
        if s > nt[-1]:
            continue
        for j in range(1, n):
            assert np.allclose(_pos(NX, NY, nt, j, s), _pos(X, Y, tt, j, s), atol=1e-9)
    for x, y, t in zip(wx, wy, wt, strict=True):
        assert np.allclose(_pos(NX, NY, nt, 0, t), (x, y), atol=1e-9)
    step = np.hypot(np.diff(NX, axis=0), np.diff(NY, axis=0))
    assert step.max() <= SPACING + 1e-9
    assert arrivals(NX, NY, nt)[0] <= max(wt[-1], 0.0) + 1e-9


def _makespan(paths: np.ndarray) -> float:
    """The latest arrival at unit speed, each row lasting as long as its longest move
    (as ``benchmarks/bench_fleet.py`` measures it)."""
    step = np.hypot(*np.diff(paths, axis=1).transpose(2, 0, 1))
    moving = step > 0
    last = np.where(moving.any(axis=1), step.shape[1] - np.argmax(moving[:, ::-1], axis=1), 0)
    dur = step.max(axis=0)
    return float(max(dur[:a].sum() for a in last))


def _map(name: str = "random-32-32-20"):
    return load_grid_map(MAPF / f"{name}.map")


@pytest.mark.parametrize("seed", [3, 7])
def test_timed_repair_inside_plan_paths(seed: int) -> None:
    """A fleet on a small map, the stage spied on: both checkers accept the plan, the
    last arrival is no later than the retiming's, and the plan is the same on a second
    call (deterministic)."""
    gm = _map()
    S, G = random_instance(gm, 150, seed)
    seen = {}
    real = gspi.timed_repair

    def spy(rows, times, *args, **kw):
        out = real(rows, times, *args, **kw)
        seen.update(before=_makespan(rows), done=out[2])
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_repair", spy)
        plan = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert plan.success and seen
    assert _makespan(plan.paths) <= seen["before"] + 1e-6
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []
    check_plan(gm.scene, S, G, plan)
    again = plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    assert np.array_equal(again.paths, plan.paths)


@settings(max_examples=60, deadline=None)
@given(keys=st.lists(st.integers(0, 1 << 40), max_size=400), small=st.booleans())
def test_the_searchs_table_is_a_dict(keys, small) -> None:
    """The timed search's open-addressing table (``_slot``, grown by ``_grown`` when half
    full) finds every key put in it with its last value, and no other, like a dict;
    from a table of 4 slots (many growths, long probes) or of the search's 4,096."""
    from lamp.mrmp.timed_search import _grown, _slot

    size = 4 if small else 1 << 12
    tk, tv = np.full(size, -1, np.int64), np.empty(size, np.int64)
    ref: dict[int, int] = {}
    for n, key in enumerate(keys):
        s = _slot(tk, key)
        assert (tk[s] == key) == (key in ref)
        if tk[s] != key:
            if 2 * (len(ref) + 1) > len(tk):
                tk, tv = _grown(tk, tv)
                s = _slot(tk, key)
            tk[s] = key
        tv[s] = n
        ref[key] = n
    assert int((tk != -1).sum()) == len(ref)
    for key, val in ref.items():
        s = _slot(tk, key)
        assert tk[s] == key and tv[s] == val
    for key in (k + 1 for k in keys[:20]):
        if key not in ref:
            assert tk[_slot(tk, key)] == -1
