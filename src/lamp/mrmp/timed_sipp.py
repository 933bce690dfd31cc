"""Safe Interval Path Planning (SIPP; M. Phillips and M. Likhachev, "SIPP: Safe Interval
Path Planning for Dynamic Environments", ICRA 2011) for :mod:`lamp.mrmp.timed_repair`:
one robot's early way to its goal against the other robots' retimed motion, over
(vertex, safe interval) rather than (vertex, time) (:mod:`lamp.mrmp.timed_search`).

The graph, the moves, their durations in whole quanta ``q``, the heuristic and its
pruning against the target, and the check of every move are those of
:func:`~lamp.mrmp.timed_search.timed_search`; a wait lasts any whole number of quanta
(there: :data:`~lamp.mrmp.timed_search.TIMED_WAIT`). A state is a vertex, one of its
safe intervals (:mod:`lamp.mrmp.safe_intervals`: a run of times joined by waits that no
other robot refuses) and its earliest arrival there found so far: a robot that reaches
an interval earlier may wait to any later time of it, so one state per interval stands
for all of them (the paper's Theorem 1). Comments ``{A1.n}`` and ``{A2.n}`` cite the
lines of the paper's Algorithm 1 (the A* loop) and Algorithm 2 (``getSuccessors``).

Departures from the paper, each for a reason:

* Edges: the paper's collisions are at configurations; here two robots' motions over a
  piece of time are checked together (Gspi's rule), so a safe arrival is not a safe
  move. The earliest arrival in an interval {A2.10} is found by trying departures one
  quantum apart from the earliest, each move checked with
  :func:`~lamp.mrmp.timed_checks.motion_near` (the check of
  :func:`~lamp.mrmp.timed_search.timed_search`), the first clear one kept; an interval
  starts at its first time with no other robot within 2r, as a move arriving earlier
  would be refused ({A2.8}'s test, with the interval's start moved there).
* Waits checked: the wait before a kept departure is checked with
  :func:`~lamp.mrmp.timed_checks.motion_near` too (the intervals are computed in floating
  point); when it is refused no later departure from the state is tried. Every piece of
  the way returned is thus checked as :func:`~lamp.mrmp.timed_search.timed_search`
  checks its own.
* Intervals lazily, and bounded: a vertex's intervals are computed when a move first
  reaches it, over the times from its straight-line distance from the start to the
  target less its straight-line distance to the goal (at unit speed no way is at the
  vertex outside these).
* Goal: reached once the robot may stay on it to the end
  (:func:`~lamp.mrmp.timed_checks.free_time`): an arrival there is followed by the wait
  to that time when it is clear, as a state of its own whose f is its time; the search
  ends when such a state is removed from OPEN ({A1.3}: "s_goal expanded").
* Heuristic: :func:`~lamp.mrmp.timed_search.timed_search`'s (the lattice distance over
  :data:`~lamp.mrmp.timed_search.OCTILE`, or
  :data:`~lamp.mrmp.timed_search.OCTILE_BOUND` with ``tight``), not always a lower
  bound; so a state reached earlier than before is inserted again ({A1.9}-{A1.13}, the
  older entry skipped when removed), and f at least the target prunes. Ties: the latest
  time first.
* Status and bound: it stops after ``budget`` expansions; it returns a status
  (:data:`SIPP_FOUND`, :data:`SIPP_NONE`, :data:`SIPP_BUDGET`, :data:`SIPP_GOAL_BUSY`).

Reference: ``tests/test_mrmp_timed_sipp.py`` compares it with
:func:`~lamp.mrmp.timed_search.timed_search` on fleets' rows (a way whenever that finds
one; no later with the lower-bound heuristic), and checks every way it finds by brute
force.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.borrow import borrowed
from lamp.mrmp.goal_distances import hval
from lamp.mrmp.heuristic_reads import goal_views, read_in
from lamp.mrmp.neighbours import doubled
from lamp.mrmp.safe_intervals import blocked_waits, runs_of
from lamp.mrmp.timed_checks import free_time, gather_rows, motion_clear, motion_near, row_at
from lamp.mrmp.timed_search import OCTILE, OCTILE_BOUND, heap_pop, heap_push, move_to

__all__ = ["SIPP_BUDGET", "SIPP_FOUND", "SIPP_GOAL_BUSY", "SIPP_NONE", "sipp_search"]

#: It found a way.
SIPP_FOUND = 0
#: No way arrives before the target (every state expanded or pruned).
SIPP_NONE = 1
#: It spent its budget of expansions first.
SIPP_BUDGET = 2
#: The goal is not free for good before the target: it searched nothing.
SIPP_GOAL_BUSY = 3


@nb.njit(cache=True)
def _intervals(u: int, i: int, v0: int, g: int, coords: np.ndarray, q: float, target: int,
               env: tuple, vrun: np.ndarray, rl: tuple, blk: np.ndarray) -> tuple:
    """Vertex u's safe intervals for robot i (start vertex ``v0``, goal vertex ``g``)
    appended to ``rl = (lo, hi, best, n)`` (``best``: the earliest arrival inserted,
    large for none), ``vrun[u]`` set to their first entry and count, over the times of
    the module docstring (``blk``: a buffer of 2 x ``target`` flags); returns ``rl``.
    ``env = (X, Y, tt, hh, x0, y0, cs, ny, two_r, ends_goal, ways, segs)``."""
    two_r, ways, segs = env[8], env[10], env[11]
    lo, hi, best, n = rl
    ux, uy = coords[u, 0], coords[u, 1]
    from_start = math.hypot(ux - coords[v0, 0], uy - coords[v0, 1]) / q
    to_goal = math.hypot(ux - coords[g, 0], uy - coords[g, 1]) / q
    t_lo = max(0, int(from_start) - 1)
    t_hi = min(target, int(math.floor(target - to_goal + 1e-6)) + 1)
    vrun[u, 0] = n
    vrun[u, 1] = 0
    if t_hi <= t_lo:
        return rl
    b = blk[0, : t_hi - t_lo]
    ins = blk[1, : t_hi - t_lo]
    b[:] = False
    ins[:] = False
    blocked_waits(i, ux, uy, t_lo, q, segs, two_r, ways, b, ins)
    if u == v0:  # the start, at time 0, whoever is near
        ins[0] = False
    if u == g:  # two robots ending on goals may come closer than 2r
        ins[:] = False
    lo, hi, n2 = runs_of(b, ins, t_lo, lo, hi, n)
    while best.shape[0] < lo.shape[0]:
        best = doubled(best, n)
    best[n:n2] = 1 << 60
    vrun[u, 1] = n2 - n
    return lo, hi, best, n2


@nb.njit(cache=True, inline="always")
def _first_run(hi: np.ndarray, a: int, c: int, t: int) -> int:
    """The first of the runs ``a .. a + c - 1`` (in time order) that ends at ``t`` or
    later (``a + c`` when none)."""
    b = a + c
    while a < b:
        mid = (a + b) // 2
        if hi[mid] < t:
            a = mid + 1
        else:
            b = mid
    return a


@nb.njit(cache=True)
def sipp_search(i: int, m: int, gr: tuple, V: int, gv0: int, hs: tuple, X: np.ndarray,
                Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
                ny: int, two_r: float, ends_goal: np.ndarray, q: float, target: int,
                budget: int, ob: tuple, ways: tuple, segs: tuple, tight: bool = False
                ) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Robot i's way to goal m arriving before ``target`` quanta, over safe intervals
    (module docstring); the arguments are
    :func:`~lamp.mrmp.timed_search.timed_search`'s (``alone`` 0) and the rows' segments
    ``segs`` (:func:`lamp.mrmp.safe_intervals.segment_index`). Returns its vertices
    and their times in quanta (a wait: a vertex twice; empty when none), the states
    expanded, and the status. The arguments are borrowed (:mod:`lamp.mrmp.borrow`): each
    state's expansion binds them without counting references."""
    gr, hs, X, Y, tt, hh, ends_goal, ob, ways, segs = borrowed(
        (gr, hs, X, Y, tt, hh, ends_goal, ob, ways, segs))
    coords = gr[0]
    g = gv0 + m
    none = np.zeros(0, np.int64)
    free = free_time(i, coords[g, 0], coords[g, 1], X, Y, tt, hh, x0, y0, cs, ny, two_r,
                     ends_goal, ways)
    if not free < target * q:
        return none, none, 0, SIPP_GOAL_BUSY
    tf = max(0, int(math.ceil(free / q)) - 1)  # the first whole time from which it is free
    while tf * q < free:
        tf += 1
    env = (X, Y, tt, hh, x0, y0, cs, ny, two_r, ends_goal, ways, segs)
    vrun = np.full((coords.shape[0], 2), -1, np.int64)
    blk = np.empty((2, target + 1), np.bool_)
    buf = np.empty(256, np.int64)
    rl = (buf, buf.copy(), buf.copy(), 0)
    v0 = V + i
    rl = _intervals(v0, i, v0, g, coords, q, target, env, vrun, rl, blk)
    if vrun[v0, 1] == 0:
        return none, none, 0, SIPP_NONE
    # {A1.1}-{A1.2}: the start at time 0, in its first interval; states: vertex, time,
    # interval (-1: on the goal for good), departure from the parent's vertex, parent
    sv = np.empty(1 << 10, np.int64)
    states = (sv, np.zeros(1 << 10, np.int64), np.full(1 << 10, vrun[v0, 0]),
              np.zeros(1 << 10, np.int64), np.full(1 << 10, -1, np.int64), 1)
    sv[0] = v0
    rl[2][vrun[v0, 0]] = 0
    hf = np.empty(1 << 10)
    heap = (hf, np.empty(1 << 10, np.int64), np.empty(1 << 10, np.int64), 1)
    heap_push(hf, heap[1], heap[2], 0, 0.0, 0, 0)
    gath = (np.empty(64, np.int64), np.zeros(tt.shape[0] + 1, np.int64))
    div = q * (OCTILE_BOUND if tight else OCTILE)
    work = 0
    found = -1
    while heap[3] > 0 and work < budget:  # {A1.3}
        hf, ht, hi, nh = heap
        s = heap_pop(hf, ht, hi, nh)  # {A1.4}
        heap = (hf, ht, hi, nh - 1)
        j = states[2][s]
        if j < 0:  # on the goal for good: s_goal expanded
            found = s
            break
        if states[1][s] > rl[2][j]:  # reached earlier since: that entry stands for it
            continue
        work += 1
        states, heap, rl, gath = _expand(s, i, m, g, tf, gr, V, gv0, hs, q, target, div, ob,
                                         env, vrun, rl, blk, states, heap, gath)
    if found < 0:
        return none, none, work, SIPP_BUDGET if heap[3] > 0 else SIPP_NONE
    pv, pt = _unwind(found, states[0], states[1], states[3], states[4])
    return pv, pt, work, SIPP_FOUND


@nb.njit(cache=True)
def _expand(s: int, i: int, m: int, g: int, tf: int, gr: tuple, V: int, gv0: int,
            hs: tuple, q: float, target: int, div: float, ob: tuple, env: tuple,
            vrun: np.ndarray, rl: tuple, blk: np.ndarray, states: tuple, heap: tuple,
            gath: tuple) -> tuple:
    """{A1.5}-{A1.13} for state s: its successors ({A2.1}-{A2.15}) inserted when they
    arrive earlier in their interval than any state before. Returns ``states, heap, rl,
    gath``, grown where full."""
    coords, nbr, _, xptr, xidx = gr
    va, vb, ids, sdone, sval = hs[11], hs[12], hs[13], hs[9], hs[10]
    X, Y, tt, hh, x0, y0, cs, ny, two_r, ends_goal, ways, _ = env
    gk, gptr = gath
    v, t = states[0][s], states[1][s]
    whi = rl[1][states[2][s]]  # the latest departure: the end of its interval {A2.6}
    ok_to = t  # the waits at v checked up to this time
    ax, ay = coords[v, 0], coords[v, 1]
    r0 = row_at(tt, t * q)
    nrows = 0
    dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
    deg = 1 + (8 if v < V else 0) + (xptr[v + 1] - xptr[v])
    for e in range(1, deg + (8 if v < V else 0)):  # {A2.2}: every move but the wait
        u = move_to(e, v, V, gv0, deg, 0, nbr, xptr, xidx, va, vb, ids, coords, ob)
        if u < 0:
            continue
        bx, by = coords[u, 0], coords[u, 1]
        d = int(math.ceil(math.hypot(bx - ax, by - ay) / q - 1e-9))  # {A2.4}
        if t + d >= target:
            continue
        hu = read_in(m, u, V, va, vb, sdone, sval, dd, dn, wa0, wb0, wna, wnb)
        if hu < 0.0:
            hu = hval(m, u, gr, V, gv0, hs)
            dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
        lim = min(target - 1e-9, target - 1e-6 - hu / div)  # t2 + h / div < target
        if vrun[u, 0] < 0:
            rl = _intervals(u, i, V + i, g, coords, q, target, env, vrun, rl, blk)
        a, c = vrun[u, 0], vrun[u, 1]
        for j in range(_first_run(rl[1], a, c, t + d), a + c):  # {A2.5}-{A2.8}
            lo, hi, best, _ = rl
            if lo[j] > whi + d or not lo[j] < lim:
                break
            # {A2.10}: the earliest departure in s's interval whose move is clear
            td = max(t, lo[j] - d)
            dep = -1
            while td <= whi and td + d <= hi[j] and td + d < lim and best[j] > td + d:
                r_end = row_at(tt, (td + d) * q)
                if r_end - r0 >= nrows:
                    gk, nrows = gather_rows(i, ax, ay, r0, nrows, r_end, hh, x0, y0, cs, ny,
                                            ways[0], gk, gptr)
                rd = row_at(tt, td * q)
                if motion_near(i, ax, ay, bx, by, td * q, (td + d) * q, u == g, X, Y, tt,
                               two_r, ends_goal, ways, gk, gptr[rd - r0:], rd):
                    dep = td
                    break
                td += 1
            if dep < 0:  # {A2.11}-{A2.12}
                continue
            if dep > ok_to:
                if not motion_near(i, ax, ay, ax, ay, t * q, dep * q, v == g, X, Y, tt,
                                   two_r, ends_goal, ways, gk, gptr, r0):
                    whi = dep - 1  # no later departure either
                    break
                ok_to = dep
            states, heap = _insert(u, j, dep + d, dep, s, g, tf, dep + d + hu / div, target,
                                   q, i, coords, env, rl[2], states,
                                   heap)  # {A2.13}-{A2.14}
    return states, heap, rl, (gk, gptr)


@nb.njit(cache=True)
def _insert(u: int, j: int, t2: int, dep: int, s: int, g: int, tf: int, f: float,
            target: int, q: float, i: int, coords: np.ndarray, env: tuple,
            best: np.ndarray, states: tuple, heap: tuple) -> tuple[tuple, tuple]:
    """{A1.10}-{A1.13}: vertex u in its interval j at ``t2``, having left s's vertex at
    ``dep``, inserted with ``f`` (``best[j]`` set). On robot i's goal g the wait to the
    time from which it is free (``tf``) follows as a state of its own, f its time, when
    it is clear and before the target, and u is not inserted itself: leaving the goal
    and coming back arrives no earlier. Returns ``states, heap``, grown where full."""
    sv, st, sr, sd, sp, n = states
    hf, ht, hi, nh = heap
    if n + 2 > sv.shape[0]:
        sv, st, sr = doubled(sv, n), doubled(st, n), doubled(sr, n)
        sd, sp = doubled(sd, n), doubled(sp, n)
    if nh + 1 > hf.shape[0]:
        hf, ht, hi = doubled(hf, nh), doubled(ht, nh), doubled(hi, nh)
    sv[n], st[n], sr[n], sd[n], sp[n] = u, t2, j, dep, s
    best[j] = t2
    n += 1
    if u == g:
        X, Y, tt, hh, x0, y0, cs, ny, two_r, ends_goal, ways, _ = env
        gx, gy = coords[g, 0], coords[g, 1]
        tg = max(t2, tf)
        if tg < target and (tg == t2 or motion_clear(i, gx, gy, gx, gy, t2 * q, tg * q, True,
                                                     X, Y, tt, hh, x0, y0, cs, ny, two_r,
                                                     ends_goal, ways)):
            sv[n], st[n], sr[n], sd[n], sp[n] = g, tg, -1, t2, n - 1
            heap_push(hf, ht, hi, nh, float(tg), tg, n)
            return (sv, st, sr, sd, sp, n + 1), (hf, ht, hi, nh + 1)
    heap_push(hf, ht, hi, nh, f, t2, n - 1)
    return (sv, st, sr, sd, sp, n), (hf, ht, hi, nh + 1)


@nb.njit(cache=True)
def _unwind(found: int, sv: np.ndarray, st: np.ndarray, sd: np.ndarray, sp: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """The vertices and times of the way from the start to state ``found`` (parents
    ``sp``): each state's arrival, preceded by the wait at its parent's vertex to its
    departure ``sd`` when that is later than the parent's arrival; no entry twice."""
    c = 0
    s = found
    while s >= 0:
        c += 1
        s = sp[s]
    pv = np.empty(2 * c, np.int64)
    pt = np.empty(2 * c, np.int64)
    k = 2 * c
    s = found
    while s >= 0:
        p = sp[s]
        if k == 2 * c or pv[k] != sv[s] or pt[k] != st[s]:
            k -= 1
            pv[k], pt[k] = sv[s], st[s]
        if p >= 0 and sd[s] > st[p] and (pv[k] != sv[p] or pt[k] != sd[s]):
            k -= 1
            pv[k], pt[k] = sv[p], sd[s]
        s = p
    return pv[k:].copy(), pt[k:].copy()
