"""The timed repair's search over safe intervals (``lamp.mrmp.timed_sipp``,
``safe_intervals``): the intervals against the motion check of every unit wait and the
distances of every robot; the search against the search over (vertex, time)
(``timed_search``, the reference) on fleets' retimed rows, every way it returns checked
piece by piece by brute force; and fleets planned with each search, every plan checked
by the independent checkers."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from fleet_checker import check_fleet_plan
from hypothesis import given, settings
from hypothesis import strategies as st
from mrmp_checker import check_plan
from test_mrmp_timed_repair import (
    MAPF,
    SPACING,
    R,
    _blocked_by,
    _makespan,
    _random_rows,
    _way_of_robot_1,
)

import lamp.mrmp.gspi as gspi
from lamp.mrmp import plan_paths
from lamp.mrmp.gspi_kernels import conflict
from lamp.mrmp.obstacle_grid import get_grid
from lamp.mrmp.repair_hash import hash_rows
from lamp.mrmp.safe_intervals import blocked_waits, runs_of, segment_index, unsafe_span
from lamp.mrmp.timed_checks import arrivals, free_time, motion_clear
from lamp.mrmp.timed_search import timed_search
from lamp.mrmp.timed_sipp import (
    SIPP_BUDGET,
    SIPP_FOUND,
    SIPP_GOAL_BUSY,
    SIPP_NONE,
    sipp_search,
)
from lamp.scene.mapf import load_grid_map, random_instance

CS = 2 * R + 0.04 + 2 * SPACING + 1e-6


@settings(max_examples=400, deadline=None)
@given(seed=st.integers(0, 100_000), still=st.booleans())
def test_unsafe_span_is_where_waits_are_refused(seed, still) -> None:
    """A point and a robot moving linearly (or still) over a piece: a wait over a random
    part ``[s0, s1]`` of the piece is refused by Gspi's rule (with its tolerance) exactly
    when it meets the open interval ``(a, s)``, and the robot is within 2r at a random
    time exactly when it lies in ``(c, b)``."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(0, 0.3, 2)
    a0 = p + rng.uniform(-0.2, 0.2, 2)
    a1 = a0 if still else a0 + rng.uniform(-0.25, 0.25, 2)
    e0 = float(rng.uniform(0, 1))
    e1 = e0 + float(rng.uniform(0.01, 0.3))
    a, s, c, b = unsafe_span(p[0], p[1], a0[0], a0[1], a1[0], a1[1], e0, e1, 2 * R)

    def at(t):
        return a0 + (a1 - a0) * (t - e0) / (e1 - e0)

    s0, s1 = np.sort(rng.uniform(e0, e1, 2))
    refused = conflict(p[0], p[1], p[0], p[1], *at(s0), *at(s1), 2 * R, False)
    assert refused == (s0 < s and s1 > a)
    t = float(rng.uniform(e0, e1))
    assert (np.hypot(*(at(t) - p)) < 2 * R) == (c < t < b)


def _no_ways(n):
    return (np.zeros(n, np.bool_), np.zeros(1), np.zeros(1), np.zeros(1),
            np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros((0, 4)))


def _pos(X, Y, tt, k, t):
    return np.array([np.interp(t, tt, X[:, k]), np.interp(t, tt, Y[:, k])])


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.integers(2, 10), rows=st.integers(2, 14),
       as_way=st.booleans(), t_lo=st.integers(0, 5))
def test_blocked_waits_match_the_motion_check(seed, n, rows, as_way, t_lo) -> None:
    """Random crowded rows and a point: each unit wait from ``t_lo`` on is marked refused
    exactly when ``motion_clear`` refuses it, and each time marked as within 2r of a
    robot exactly when one is (robot 1 also as a new way: its rows then ignored); the
    intervals built from them are the runs of times joined by waits not refused, each
    from its first time no robot is within 2r of."""
    rng = np.random.default_rng(seed)
    X, Y, tt = _random_rows(rng, n, rows, box=0.35)
    p = rng.uniform(0.1, 0.35, 2)
    q = float(rng.uniform(0.002, 0.01))
    T = int(tt[-1] / q) + 4 - t_lo
    hh, ny = hash_rows(X, Y, -0.5, -0.5, 1.5, 1.5, CS, True)
    ways = _way_of_robot_1(X, Y, tt) if as_way else _no_ways(n)
    segs = segment_index(X, Y, tt, 2 * R, -0.5, -0.5, 1.5, 1.5)
    blk = np.zeros(max(T, 1), np.bool_)
    ins = np.zeros(max(T, 1), np.bool_)
    blocked_waits(0, p[0], p[1], t_lo, q, segs, 2 * R, ways, blk, ins)
    ends = np.zeros(n, np.bool_)
    for j in range(blk.shape[0]):
        t = t_lo + j
        clear = motion_clear(0, p[0], p[1], p[0], p[1], t * q, (t + 1) * q, False, X, Y, tt,
                             hh, -0.5, -0.5, CS, ny, 2 * R, ends, ways)
        assert blk[j] == (not clear)
        near = any(np.hypot(*(_pos(X, Y, tt, k, t * q) - p)) < 2 * R for k in range(1, n))
        assert ins[j] == near
    lo, hi, c = runs_of(blk, ins, t_lo, np.empty(1, np.int64), np.empty(1, np.int64), 0)
    want, start = [], 0
    for j in range(blk.shape[0]):
        if blk[j] or j == blk.shape[0] - 1:
            first = next((u for u in range(start, j + 1) if not ins[u]), None)
            if first is not None:
                want.append((t_lo + first, t_lo + j))
            start = j + 1
    assert list(zip(lo[:c].tolist(), hi[:c].tolist(), strict=True)) == want


@functools.cache
def _fleet(n: int, seed: int) -> dict:
    """The timed repair's inputs for a fleet of n on ``random-32-32-20`` (its arguments
    in ``plan_paths``, spied on), set up as ``timed_repair`` sets them up for its
    searches."""
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, n, seed)
    seen = {}
    real = gspi.timed_repair

    def spy(*args, **kw):
        seen["args"] = args
        return real(*args, **kw)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_repair", spy)
        plan_paths(gm.scene, S, G, seed=seed, time_limit=600.0)
    (rows, times, gr, V, gv0, hs, goal, two_r, q, max_move, max_spacing, geometry,
     workspace, need) = seen["args"]
    X = np.ascontiguousarray(rows[:, :, 0].T)
    Y = np.ascontiguousarray(rows[:, :, 1].T)
    tt = np.asarray(times, np.float64)
    cs = two_r + max(1.6 * max_move, max_spacing) + 2.0 * max_spacing + 1e-6
    coords = gr[0]
    x0, y0 = coords[:, 0].min(), coords[:, 1].min()
    x1, y1 = coords[:, 0].max(), coords[:, 1].max()
    hh, ny = hash_rows(X, Y, x0, y0, x1, y1, cs, True)
    g = get_grid(geometry)
    ob = (np.full(1, float(need)), geometry.circles, geometry.verts, geometry.ptr,
          float(workspace[0]), float(workspace[1]), g.ptr, g.idx, g.box, g.nx, g.ny, g.cell,
          np.zeros(8 * V, np.int8))
    return dict(X=X, Y=Y, tt=tt, gr=gr, V=V, gv0=gv0, hs=hs, goal=np.asarray(goal),
                two_r=float(two_r), q=float(q), cs=cs, x0=x0, y0=y0, hh=hh, ny=ny, ob=ob,
                segs=segment_index(X, Y, tt, float(two_r), x0, y0, x1, y1),
                arr=arrivals(X, Y, tt), ways=_no_ways(X.shape[1]))


def _search(f: dict, i: int, target: int, budget: int, tight: bool, sipp: bool):
    args = (i, int(f["goal"][i]), f["gr"], f["V"], f["gv0"], f["hs"], f["X"], f["Y"],
            f["tt"], f["hh"], f["x0"], f["y0"], f["cs"], f["ny"], f["two_r"],
            f["goal"] >= 0, f["q"], target, budget, f["ob"], f["ways"])
    if sipp:
        return sipp_search(*args, f["segs"], tight)
    pv, pt, work = timed_search(*args, f["arr"], 0, tight)
    return pv, pt, work, None


def _way_ok(f: dict, i: int, pv: np.ndarray, pt: np.ndarray) -> bool:
    """Robot i's way (vertices ``pv`` at ``pt`` quanta, then still on the last to the end)
    against every other robot's rows, each move and wait cut at every row time inside
    (``test_mrmp_timed_repair``'s brute-force reference)."""
    X, Y, tt, q, coords = f["X"], f["Y"], f["tt"], f["q"], f["gr"][0]
    pieces = [(pv[k], pv[k + 1], pt[k] * q, pt[k + 1] * q) for k in range(len(pv) - 1)]
    pieces.append((pv[-1], pv[-1], pt[-1] * q, max(pt[-1] * q, tt[-1]) + 1.0))
    return not any(_blocked_by(k, coords[u], coords[v], t0, t1, X, Y, tt)
                   for u, v, t0, t1 in pieces if t1 > t0
                   for k in range(X.shape[1]) if k != i)


@settings(max_examples=30, deadline=None)
@given(n=st.sampled_from([40, 70]), seed=st.integers(0, 2), rank=st.integers(0, 7),
       early=st.integers(0, 40), tight=st.booleans())
def test_sipp_arrives_no_later_than_the_search_over_times(n, seed, rank, early,
                                                          tight) -> None:
    """A fleet's retimed rows, one of its last robots and a target up to 40 quanta before
    the last arrival: with budget to spare, the safe-interval search finds a way
    whenever the search over (vertex, time) does; with the lower-bound heuristic (both
    then give their earliest arrival) it arrives no later, usually in far fewer states.
    Every way it finds keeps clear of every other robot by brute force."""
    f = _fleet(n, seed)
    i = int(np.argsort(-f["arr"], kind="stable")[rank])
    target = int(math.ceil(f["arr"].max() / f["q"] - 1e-9)) - early
    pv, pt, _, _ = _search(f, i, target, 10**6, tight, sipp=False)
    sv, st_, work, status = _search(f, i, target, 10**6, tight, sipp=True)
    if len(pv):
        assert status == SIPP_FOUND
        if tight:
            assert st_[-1] <= pt[-1]
    if status == SIPP_FOUND:
        assert sv[0] == f["V"] + i and sv[-1] == f["gv0"] + f["goal"][i]
        assert st_[0] == 0 and st_[-1] < target and np.all(np.diff(st_) > 0)
        assert _way_ok(f, i, sv, st_)
    else:
        assert status != SIPP_BUDGET and work < 10**6
        assert len(pv) == 0


def test_sipp_statuses() -> None:
    """A robot whose goal another robot crosses: with a target before that, nothing is
    searched; with the target of the last arrival and a budget of one expansion, it
    stops there without a way; a target before its straight line allows: no way."""
    f = _fleet(40, 0)
    args = (f["X"], f["Y"], f["tt"], f["hh"], f["x0"], f["y0"], f["cs"], f["ny"],
            f["two_r"], f["goal"] >= 0, f["ways"])
    coords, q = f["gr"][0], f["q"]
    free = [free_time(i, *coords[f["gv0"] + f["goal"][i]], *args) for i in range(40)]
    i = int(np.argmax(free))
    assert free[i] > 2 * q
    _, _, work, status = _search(f, i, int(free[i] / q) - 1, 10**6, False, sipp=True)
    assert (status, work) == (SIPP_GOAL_BUSY, 0)
    target = int(math.ceil(f["arr"].max() / q - 1e-9))
    pv, _, work, status = _search(f, i, target + 5, 1, False, sipp=True)
    assert (len(pv), work, status) == (0, 1, SIPP_BUDGET)
    j = int(np.argmax(f["arr"]))
    line = np.hypot(*(coords[f["V"] + j] - coords[f["gv0"] + f["goal"][j]]))
    pv, _, _, status = _search(f, j, int(line / q) - 1, 10**6, False, sipp=True)
    assert (len(pv), status) == (0, SIPP_NONE)


@pytest.mark.parametrize("sipp", [True, False])
def test_fleets_with_either_search_are_valid(sipp: bool) -> None:
    """200 robots on ``random-32-32-20`` repaired with either search: both independent
    checkers accept the plan, the last arrival is no later than the retiming's, and a
    second call gives the same plan."""
    gm = load_grid_map(MAPF / "random-32-32-20.map")
    S, G = random_instance(gm, 200, 4)
    seen = {}
    real = gspi.timed_repair

    def spy(rows, *args, **kw):
        out = real(rows, *args, **{**kw, "sipp": sipp})
        seen.update(before=_makespan(rows), done=out[2])
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(gspi, "timed_repair", spy)
        plan = plan_paths(gm.scene, S, G, seed=4, time_limit=600.0)
        again = plan_paths(gm.scene, S, G, seed=4, time_limit=600.0)
    assert plan.success and seen["done"] >= 1
    assert _makespan(plan.paths) <= seen["before"] + 1e-6
    assert check_fleet_plan(gm.scene.to_dict(), S, G, plan, R) == []
    check_plan(gm.scene, S, G, plan)
    assert np.array_equal(again.paths, plan.paths)
