"""Gspi's compiled core (Numba): PIBT steps over neighbour lists (the goal swaps and the
deadlock rule: :mod:`lamp.mrmp.gspi_swaps`).

The driver, :mod:`lamp.mrmp.gspi`, builds the arrays and calls :func:`run_steps`;
everything else here is its machinery. Two bundles of arrays travel through every kernel,
as named tuples (Numba compiles them as tuples, so the kernels may unpack them
positionally):

- :class:`Graph` ``gr``: vertices ``0..V-1`` are lattice nodes, ``V..V+N-1`` the robots'
  start vertices and ``gv0 = V+N ..`` the goal vertices; ``coords`` holds every vertex's
  position, ``nbr``/``dlen`` the lattice's 8-neighbourhood and its step lengths, and
  ``xptr``/``xidx`` (CSR) the extra edges of the special vertices.
- :class:`~lamp.mrmp.goal_distances.GoalDistances` ``hs``: one lazy Dijkstra per goal.

Robot-robot checks use *neighbour lists* built once per step from a spatial hash of the
current positions: two robots whose centres are more than ``2r + 2 * maxmove`` apart
(``maxmove``: the graph's longest edge) cannot come closer than ``2r`` within one step, so
each robot checks only the robots within that distance, in index order, which gives
exactly the decisions of an all-pairs scan. Goal swapping considers the pairs within
``swap_radius`` (all pairs for teams below :data:`ALL_PAIRS_BELOW` robots).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from lamp.geometry.kernels import point_segment_distance
from lamp.mrmp.borrow import borrowed
from lamp.mrmp.goal_distances import hval
from lamp.mrmp.gspi_swaps import break_deadlocks, swap_goals
from lamp.mrmp.heuristic_reads import hval_fast, read_in
from lamp.mrmp.neighbours import ALL_PAIRS_BELOW, neighbour_lists, within

__all__ = ["ALL_PAIRS_BELOW", "Graph", "conflict", "neighbour_lists", "run_steps"]

_UNDECIDED, _TENTATIVE, _DECIDED = 0, 1, 2


class Graph(NamedTuple):
    """The search graph of one Gspi attempt (see the module docstring)."""

    coords: np.ndarray  # (V+N+M, 2) vertex positions
    nbr: np.ndarray  # (V, 8) lattice neighbours, -1 where none
    dlen: np.ndarray  # (8,) length of each neighbour direction
    xptr: np.ndarray  # (V+N+M+1,) CSR offsets of the special vertices' extra edges
    xidx: np.ndarray  # targets of those edges


@nb.njit(cache=True, inline="always")
def _hash01(seed: int, t: int, i: int, c: int) -> float:
    """Deterministic uniform [0, 1) from integers (splitmix64 finaliser)."""
    z = (
        np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15)
        + np.uint64(t) * np.uint64(0xBF58476D1CE4E5B9)
        + np.uint64(i) * np.uint64(0x94D049BB133111EB)
        + np.uint64(c)
    )
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@nb.njit(cache=True)
def conflict(
    ax: float, ay: float, bx: float, by: float,
    cx: float, cy: float, dx: float, dy: float,
    two_r: float, both_goal_end: bool,
) -> bool:
    """Whether motion a->b of one robot and c->d of another (same time span, linear)
    come closer than allowed: min distance < min(2r, start distance[, end distance
    when both end on goals]). Two goals are two points: motions ending at one point
    never pass, goals or not."""
    d0x = ax - cx
    d0y = ay - cy
    d1x = bx - dx
    d1y = by - dy
    thr = two_r
    d0 = math.sqrt(d0x * d0x + d0y * d0y)
    if d0 < thr:
        thr = d0
    if both_goal_end:
        d1 = math.sqrt(d1x * d1x + d1y * d1y)
        if 0.0 < d1 < thr:
            thr = d1
    # closest approach: distance of the origin to the relative-offset segment d0 -> d1
    return point_segment_distance(0.0, 0.0, d0x, d0y, d1x, d1y) < thr - 1e-9


@nb.njit(cache=True, inline="always")
def _build_cands(
    i: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple, goal: np.ndarray, seed: int,
    t: int, cand: np.ndarray, ncand: np.ndarray, fleet: bool, keys: np.ndarray,
    hvc: np.ndarray,
) -> None:
    """Candidates of robot i at vertex v sorted by heuristic (wait included); ties are
    broken by a seeded hash; a robot without a goal tries waiting first. In a fleet, a
    robot on its way has no candidate more than one lattice step farther from its goal:
    pushed, it steps back one step at most, else its parent moves otherwise or waits.
    ``hvc[i, k]``: candidate k's value (with a goal), for the step's end."""
    _, nbr, _, xptr, xidx = gr
    cand[i, 0] = v
    n = 1
    if v < V:
        for e in range(8):
            u = nbr[v, e]
            if u >= 0:
                cand[i, n] = u
                n += 1
    for k in range(xptr[v], xptr[v + 1]):
        cand[i, n] = xidx[k]
        n += 1
    g = goal[i]
    h0 = 0.0
    if g < 0:
        keys[0] = -1.0
        for k in range(1, n):
            keys[k] = 1e-9 * _hash01(seed, t, i, cand[i, k])
    else:
        # goal g's settled values read straight from its window (a call per value costs
        # forty times as much); the others, and the window after a growth, from hval
        win, va, vb, sdone, sval = hs[0], hs[11], hs[12], hs[9], hs[10]
        dd = hs[2][g]
        dn = hs[3][g]
        a0, b0, na, nbw = win[g, 0], win[g, 1], win[g, 2], win[g, 3]
        for k in range(n):
            u = cand[i, k]
            hv = read_in(g, u, V, va, vb, sdone, sval, dd, dn, a0, b0, na, nbw)
            if hv < 0.0:
                hv = hval(g, u, gr, V, gv0, hs)
                dd = hs[2][g]
                dn = hs[3][g]
                a0, b0, na, nbw = win[g, 0], win[g, 1], win[g, 2], win[g, 3]
            hvc[i, k] = hv
            if k == 0:
                h0 = hv
                keys[0] = hv + 1e-9 * _hash01(seed, t, i, v)
            elif hv == np.inf:
                keys[k] = np.inf
            else:
                keys[k] = hv + 1e-9 * _hash01(seed, t, i, cand[i, k])
    # insertion sort (n <= ~20)
    for a in range(1, n):
        kk = keys[a]
        cc = cand[i, a]
        hc = hvc[i, a]
        b = a - 1
        while b >= 0 and keys[b] > kk:
            keys[b + 1] = keys[b]
            cand[i, b + 1] = cand[i, b]
            hvc[i, b + 1] = hvc[i, b]
            b -= 1
        keys[b + 1] = kk
        cand[i, b + 1] = cc
        hvc[i, b + 1] = hc
    # drop candidates with infinite heuristic except waiting (they lead nowhere useful)
    m = n
    while m > 1 and keys[m - 1] == np.inf and cand[i, m - 1] != v:
        m -= 1
    if fleet and goal[i] >= 0 and v != gv0 + goal[i]:
        lim = h0 + hs[17] + 1e-9
        while m > 1 and keys[m - 1] > lim and cand[i, m - 1] != v:
            m -= 1
    ncand[i] = m


@nb.njit(cache=True, inline="always")
def _check_move(i: int, c: int, coords: np.ndarray, cur: np.ndarray, nxt: np.ndarray,
                status: np.ndarray, mode: np.ndarray, nptr: np.ndarray, nidx: np.ndarray,
                gv0: int, two_r: float) -> tuple[bool, int]:
    """Robot i's move to c against its neighbours: (conflicts with a decided robot's
    motion or a tentative ancestor's, the first undecided robot it would hit or -1)."""
    ax = coords[cur[i], 0]
    ay = coords[cur[i], 1]
    bx = coords[c, 0]
    by = coords[c, 1]
    c_goal = c >= gv0
    blocker = -1
    for q in range(nptr[i], nptr[i + 1]):
        k = nidx[q]
        sk = status[k]
        px = coords[cur[k], 0]
        py = coords[cur[k], 1]
        stay_goal = c_goal and cur[k] >= gv0
        if sk == _UNDECIDED:
            if blocker < 0 and conflict(ax, ay, bx, by, px, py, px, py, two_r,
                                         stay_goal):
                blocker = k
        elif sk == _DECIDED:
            qx = coords[nxt[k], 0]
            qy = coords[nxt[k], 1]
            if conflict(ax, ay, bx, by, px, py, qx, qy, two_r,
                         c_goal and nxt[k] >= gv0):
                return True, -1
        else:  # tentative ancestor: its position now and its intended motion
            qx = coords[nxt[k], 0]
            qy = coords[nxt[k], 1]
            if conflict(ax, ay, bx, by, px, py, px, py, two_r, stay_goal) or (
                mode[i] == 0
                and conflict(ax, ay, bx, by, px, py, qx, qy, two_r,
                              c_goal and nxt[k] >= gv0)
            ):
                return True, -1
    return False, blocker


@nb.njit(cache=True, inline="always")
def _first_cands(i: int, cur: np.ndarray, gr: tuple, V: int, gv0: int, hs: tuple,
                 goal: np.ndarray, seed: int, t: int, cand: np.ndarray, ncand: np.ndarray,
                 fleet: bool, keys: np.ndarray, lazy: np.ndarray, hvc: np.ndarray) -> None:
    """Robot i's candidates; for a robot at rest (on its goal, or without one) only
    waiting, its first (heuristic 0, every other at least EPS), with ``lazy[i]`` set: the
    others are built when waiting fails (the same decisions, without building them for
    every robot at rest)."""
    if goal[i] < 0 or cur[i] == gv0 + goal[i]:
        cand[i, 0] = cur[i]
        hvc[i, 0] = -1.0  # not read
        ncand[i] = 1
        lazy[i] = 1
    else:
        _build_cands(i, cur[i], gr, V, gv0, hs, goal, seed, t, cand, ncand, fleet, keys, hvc)


@nb.njit(cache=True)
def _pibt_step(
    gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
    prio: np.ndarray, two_r: float, seed: int, t: int, nxt: np.ndarray,
    cand: np.ndarray, ncand: np.ndarray, ci: np.ndarray, status: np.ndarray,
    stack: np.ndarray, mode: np.ndarray, nptr: np.ndarray, nidx: np.ndarray,
    fleet: bool, hvc: np.ndarray,
) -> None:
    """One PIBT step (priority inheritance with backtracking), iterative.

    Continuous-space addition (*yield*): a robot that inherited priority and found no
    move compatible with its ancestors' intended motions scans its candidates again
    checking only the ancestors' current positions. A move found that way clears the way
    for the next step while the ancestor, which re-checks against it, waits or detours.
    Without it two robots 10 cm apart whose simultaneous moves would graze each other
    could block each other forever (the parent's wait always beating its detours).
    The arguments are borrowed (:mod:`lamp.mrmp.borrow`): the helpers of every robot
    and candidate bind them without counting references."""
    (gr, hs, cur, goal, prio, nxt, cand, ncand, ci, status, stack, mode, nptr, nidx,
     hvc) = borrowed((gr, hs, cur, goal, prio, nxt, cand, ncand, ci, status, stack, mode,
                      nptr, nidx, hvc))
    coords = gr[0]
    N = cur.shape[0]
    keys = np.empty(cand.shape[1])
    lazy = np.zeros(N, dtype=np.uint8)  # candidates beyond waiting not built yet
    for k in range(N):
        status[k] = _UNDECIDED
        nxt[k] = cur[k]
        mode[k] = 0
    order = np.argsort(-prio)
    for oi in range(N):
        r0 = order[oi]
        if status[r0] != _UNDECIDED:
            continue
        status[r0] = _TENTATIVE
        _first_cands(r0, cur, gr, V, gv0, hs, goal, seed, t, cand, ncand, fleet, keys, lazy,
                     hvc)
        ci[r0] = 0
        stack[0] = r0
        sp = 1
        while sp > 0:
            i = stack[sp - 1]
            if ci[i] >= ncand[i]:
                if lazy[i]:
                    lazy[i] = 0
                    _build_cands(i, cur[i], gr, V, gv0, hs, goal, seed, t, cand, ncand, fleet,
                                 keys, hvc)
                    continue
                if mode[i] == 0 and sp > 1:
                    mode[i] = 1  # yield pass (see docstring)
                    ci[i] = 0
                    continue
                nxt[i] = cur[i]  # every candidate failed: wait (always valid, see module doc)
                status[i] = _DECIDED
                sp -= 1
                continue
            c = cand[i, ci[i]]
            if mode[i] == 1 and c == cur[i]:
                ci[i] += 1
                continue
            nxt[i] = c
            bad, blocker = _check_move(i, c, coords, cur, nxt, status, mode, nptr, nidx, gv0,
                                       two_r)
            if bad:
                ci[i] += 1
                continue
            if blocker >= 0:
                # priority inheritance: the blocker decides first, then i re-checks c
                status[blocker] = _TENTATIVE
                _first_cands(blocker, cur, gr, V, gv0, hs, goal, seed, t, cand, ncand, fleet,
                             keys, lazy, hvc)
                ci[blocker] = 0
                mode[blocker] = 0
                stack[sp] = blocker
                sp += 1
                continue
            status[i] = _DECIDED
            sp -= 1


@nb.njit(cache=True, inline="always")
def _chosen_value(i: int, g: int, v: int, cand: np.ndarray, ncand: np.ndarray,
                  hvc: np.ndarray, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    """Robot i's value to goal g at v, where its step took it: read when its candidates
    were built (every robot that ends a step off its goal built them), else afresh."""
    for k in range(ncand[i]):
        if cand[i, k] == v:
            if hvc[i, k] >= 0.0:
                return hvc[i, k]
            break
    return hval_fast(g, v, gr, V, gv0, hs)


@nb.njit(cache=True)
def run_steps(
    gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
    prio: np.ndarray, two_r: float, seed: int, swap: bool, hist: np.ndarray,
    hsum: np.ndarray, t0: int, t1: int, maxc: int, near: float, swap_radius: float,
    stuck: np.ndarray, besth: np.ndarray, fleet: bool,
) -> tuple[int, bool]:
    """Run Gspi steps t0..t1-1; hist[t+1] receives the vertices after step t and
    hsum[t+1] the summed heuristic. Returns (rows filled - 1, all goals reached).
    ``near``: the distance beyond which two robots cannot conflict within a step
    (``2r + 2 * maxmove``); ``swap_radius``: the goal-swapping neighbourhood; ``stuck[0]``:
    per robot, the steps since its heuristic last reached a new least value ``besth``,
    ``stuck[1]`` the steps it still sits out of goal swapping after a deadlock trade
    (all kept across calls); ``fleet``: the fleet rules of ``swap_goals`` and
    ``_build_cands`` (teams of :data:`ALL_PAIRS_BELOW` or more; the swaps and the deadlock
    rule: :mod:`lamp.mrmp.gspi_swaps`). The arguments are borrowed (:mod:`lamp.mrmp.
    borrow`)."""
    gr, hs, cur, goal, prio, hist, hsum, stuck, besth = borrowed(
        (gr, hs, cur, goal, prio, hist, hsum, stuck, besth))
    N = cur.shape[0]
    nxt = np.empty(N, dtype=np.int64)
    cand = np.empty((N, maxc), dtype=np.int64)
    ncand = np.zeros(N, dtype=np.int64)
    ci = np.zeros(N, dtype=np.int64)
    status = np.zeros(N, dtype=np.int64)
    stack = np.empty(N, dtype=np.int64)
    mode = np.zeros(N, dtype=np.int64)
    hcur = np.zeros(N)  # each robot's value read after a step, for the swaps
    hvc = np.empty((N, maxc))  # the candidates' values (_build_cands)
    hgoal = np.full(N, -1, dtype=np.int64)  # the goal of hcur (-1: none read)
    small = N < ALL_PAIRS_BELOW
    # every robot checks every other in small teams (fleets: spatial hash, each step)
    aptr, aidx = neighbour_lists(np.zeros(N if small else 0), np.zeros(N if small else 0),
                                 np.inf)
    for t in range(t0, t1):
        done = True
        for i in range(N):
            if goal[i] >= 0 and cur[i] != gv0 + goal[i]:
                done = False
                break
        if done:
            return t, True
        if small:  # every robot checks every other: the same lists every step
            sptr, sidx, nptr, nidx = aptr, aidx, aptr, aidx
        else:
            px = gr[0][cur, 0]
            py = gr[0][cur, 1]
            if swap and swap_radius >= near:  # the near lists cut from the swap lists
                sptr, sidx = neighbour_lists(px, py, swap_radius)
                nptr, nidx = within(sptr, sidx, px, py, near)
            else:
                nptr, nidx = neighbour_lists(px, py, near)
                sptr, sidx = neighbour_lists(px, py, swap_radius) if swap else (nptr, nidx)
        if swap:
            swap_goals(gr, V, gv0, hs, cur, goal, prio, sptr, sidx, stuck[1], fleet, hcur,
                        hgoal)
            break_deadlocks(gr, V, gv0, hs, cur, goal, prio, nptr, nidx, stuck, besth, near)
        hgoal[:] = -1  # goals and positions change from here on
        _pibt_step(gr, V, gv0, hs, cur, goal, prio, two_r, seed, t, nxt, cand, ncand, ci,
                   status, stack, mode, nptr, nidx, fleet, hvc)
        s = 0.0
        for i in range(N):
            cur[i] = nxt[i]
            hist[t + 1, i] = nxt[i]
            g = goal[i]
            if g < 0 or cur[i] == gv0 + g:
                prio[i] = prio[i] - math.floor(prio[i])
                stuck[0, i] = 0
                besth[i] = 0.0
            else:
                prio[i] += 1.0
                hv = _chosen_value(i, g, cur[i], cand, ncand, hvc, gr, V, gv0, hs)
                hcur[i], hgoal[i] = hv, g
                s += min(hv, 1e6)
                if hv < besth[i] - 1e-9:
                    besth[i] = hv
                    stuck[0, i] = 0
                else:
                    stuck[0, i] += 1
            if stuck[1, i] > 0:
                stuck[1, i] -= 1
        hsum[t + 1] = s
    done = True
    for i in range(N):
        if goal[i] >= 0 and cur[i] != gv0 + goal[i]:
            done = False
            break
    return t1, done
