"""Gspi's compiled core (Numba): the lazy per-goal heuristic, PIBT steps and goal swaps.

The driver, :mod:`lamp.mrmp.gspi`, builds the arrays and calls :func:`seed_goal`,
:func:`start_costs` and :func:`run_steps`; everything else here is their machinery. Two
bundles of arrays travel through every kernel, as named tuples (Numba compiles them as
tuples, so the kernels may unpack them positionally):

- :class:`Graph` ``gr``: vertices ``0..V-1`` are lattice nodes, ``V..V+N-1`` the robots'
  start vertices and ``gv0 = V+N ..`` the goal vertices; ``coords`` holds every vertex's
  position, ``nbr``/``dlen`` the lattice's 8-neighbourhood and its step lengths, and
  ``xptr``/``xidx`` (CSR) the extra edges of the special vertices.
- :class:`GoalDistances` ``hs``: one resumable Dijkstra per goal (see below).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from lamp.geometry.kernels import point_segment_distance

__all__ = ["EPS", "GoalDistances", "Graph", "run_steps", "seed_goal", "start_costs"]

#: Added to every heuristic value but the goal vertex's own, so that a lattice node (or a
#: start) that coincides with a goal never ties with the goal vertex.
EPS = 1e-6
_UNDECIDED, _TENTATIVE, _DECIDED = 0, 1, 2


class Graph(NamedTuple):
    """The search graph of one Gspi attempt (see the module docstring)."""

    coords: np.ndarray  # (V+N+M, 2) vertex positions
    nbr: np.ndarray  # (V, 8) lattice neighbours, -1 where none
    dlen: np.ndarray  # (8,) length of each neighbour direction
    xptr: np.ndarray  # (V+N+M+1,) CSR offsets of the special vertices' extra edges
    xidx: np.ndarray  # targets of those edges


class GoalDistances(NamedTuple):
    """Lazy distance tables, one per goal m (pypibt's DistTable, resumable, compiled).

    ``dist[m, v]`` lattice distance to goal m (seeded with the goal's links), ``pos[m, v]``
    the node's place in goal m's indexed binary heap (-1 unseen, -2 settled), ``heap`` and
    ``hsize`` that heap, and ``sdone``/``sval`` memoised values of the special vertices.
    A value is computed only when asked for, so a 3-robot call near the object settles a
    few hundred nodes instead of the whole map.
    """

    dist: np.ndarray  # (M, V)
    pos: np.ndarray  # (M, V) int64
    heap: np.ndarray  # (M, V) int64
    hsize: np.ndarray  # (M,) int64
    sdone: np.ndarray  # (M, N+M) bool
    sval: np.ndarray  # (M, N+M)

    @staticmethod
    def empty(M: int, V: int, n_special: int) -> GoalDistances:
        return GoalDistances(
            np.full((M, V), np.inf), np.full((M, V), -1, dtype=np.int64),
            np.empty((M, V), dtype=np.int64), np.zeros(M, dtype=np.int64),
            np.zeros((M, n_special), dtype=np.bool_), np.zeros((M, n_special)))


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
def _conflict(
    ax: float, ay: float, bx: float, by: float,
    cx: float, cy: float, dx: float, dy: float,
    two_r: float, both_goal_end: bool,
) -> bool:
    """Whether motion a->b of one robot and c->d of another (same time span, linear)
    come closer than allowed: min distance < min(2r, start distance[, end distance
    when both end on goals])."""
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
        if d1 < thr:
            thr = d1
    # closest approach: distance of the origin to the relative-offset segment d0 -> d1
    return point_segment_distance(0.0, 0.0, d0x, d0y, d1x, d1y) < thr - 1e-9


# ---- lazy heuristic: one resumable Dijkstra per goal (GoalDistances) ------------------


@nb.njit(cache=True)
def _heap_up(m: int, i: int, dist: np.ndarray, pos: np.ndarray, heap: np.ndarray) -> None:
    v = heap[m, i]
    dv = dist[m, v]
    while i > 0:
        p = (i - 1) >> 1
        u = heap[m, p]
        if dist[m, u] <= dv:
            break
        heap[m, i] = u
        pos[m, u] = i
        i = p
    heap[m, i] = v
    pos[m, v] = i


@nb.njit(cache=True)
def _heap_pop(m: int, dist: np.ndarray, pos: np.ndarray, heap: np.ndarray,
              hsize: np.ndarray) -> int:
    top = heap[m, 0]
    n = hsize[m] - 1
    hsize[m] = n
    pos[m, top] = -2
    if n > 0:
        v = heap[m, n]
        dv = dist[m, v]
        i = 0
        while True:
            c = 2 * i + 1
            if c >= n:
                break
            if c + 1 < n and dist[m, heap[m, c + 1]] < dist[m, heap[m, c]]:
                c += 1
            u = heap[m, c]
            if dist[m, u] >= dv:
                break
            heap[m, i] = u
            pos[m, u] = i
            i = c
        heap[m, i] = v
        pos[m, v] = i
    return top


@nb.njit(cache=True, inline="always")
def _heap_lower(m: int, v: int, d: float, dist: np.ndarray, pos: np.ndarray, heap: np.ndarray,
                hsize: np.ndarray) -> None:
    """Set goal m's distance of vertex v to the smaller value d and restore the heap
    (v is pushed first when it has never been queued, ``pos == -1``)."""
    dist[m, v] = d
    if pos[m, v] == -1:
        heap[m, hsize[m]] = v
        pos[m, v] = hsize[m]
        hsize[m] += 1
    _heap_up(m, pos[m, v], dist, pos, heap)


@nb.njit(cache=True)
def seed_goal(m: int, nodes: np.ndarray, cost: np.ndarray, hs: tuple) -> None:
    dist, pos, heap, hsize, _, _ = hs
    for k in range(nodes.shape[0]):
        v = nodes[k]
        if cost[k] < dist[m, v]:
            _heap_lower(m, v, cost[k], dist, pos, heap, hsize)


@nb.njit(cache=True)
def _lattice_h(m: int, v: int, nbr: np.ndarray, dlen: np.ndarray, hs: tuple) -> float:
    """Distance from lattice node v to goal m, running goal m's Dijkstra until v settles."""
    dist, pos, heap, hsize, _, _ = hs
    while pos[m, v] != -2 and hsize[m] > 0:
        u = _heap_pop(m, dist, pos, heap, hsize)
        du = dist[m, u]
        for e in range(8):
            w = nbr[u, e]
            if w < 0 or pos[m, w] == -2:
                continue
            nd = du + dlen[e]
            if nd < dist[m, w]:
                _heap_lower(m, w, nd, dist, pos, heap, hsize)
    if pos[m, v] == -2:
        return dist[m, v]
    return np.inf


@nb.njit(cache=True)
def _hval(m: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    """Heuristic distance of vertex v (lattice or special) to goal m."""
    coords, nbr, dlen, xptr, xidx = gr
    if v < V:
        return _lattice_h(m, v, nbr, dlen, hs)
    _, _, _, _, sdone, sval = hs
    k = v - V
    if sdone[m, k]:
        return sval[m, k]
    best = np.inf
    if v == gv0 + m:
        best = 0.0
    else:
        for e in range(xptr[v], xptr[v + 1]):
            n = xidx[e]
            dx = coords[v, 0] - coords[n, 0]
            dy = coords[v, 1] - coords[n, 1]
            ln = math.sqrt(dx * dx + dy * dy)
            if n < V:
                c = ln + _lattice_h(m, n, nbr, dlen, hs)
            elif n == gv0 + m:
                c = ln + EPS
            else:
                continue
            if c < best:
                best = c
    sdone[m, k] = True
    sval[m, k] = best
    return best


@nb.njit(cache=True)
def _h(goal: np.ndarray, i: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    g = goal[i]
    if g < 0:
        return 0.0
    return _hval(g, v, gr, V, gv0, hs)


@nb.njit(cache=True)
def _build_cands(
    i: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple, goal: np.ndarray, seed: int,
    t: int, cand: np.ndarray, ncand: np.ndarray,
) -> None:
    """Candidates of robot i at vertex v sorted by heuristic (wait included); ties are
    broken by a seeded hash; a robot without a goal tries waiting first."""
    _, nbr, _, xptr, xidx = gr
    keys = np.empty(cand.shape[1])
    cand[i, 0] = v
    keys[0] = -1.0 if goal[i] < 0 else _h(goal, i, v, gr, V, gv0, hs)
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
    for k in range(1, n):
        hv = _h(goal, i, cand[i, k], gr, V, gv0, hs)
        if hv == np.inf:
            keys[k] = np.inf
        else:
            keys[k] = hv + 1e-9 * _hash01(seed, t, i, cand[i, k])
    if goal[i] >= 0:
        keys[0] += 1e-9 * _hash01(seed, t, i, v)
    # insertion sort (n <= ~20)
    for a in range(1, n):
        kk = keys[a]
        cc = cand[i, a]
        b = a - 1
        while b >= 0 and keys[b] > kk:
            keys[b + 1] = keys[b]
            cand[i, b + 1] = cand[i, b]
            b -= 1
        keys[b + 1] = kk
        cand[i, b + 1] = cc
    # drop candidates with infinite heuristic except waiting (they lead nowhere useful)
    m = n
    while m > 1 and keys[m - 1] == np.inf and cand[i, m - 1] != v:
        m -= 1
    ncand[i] = m


@nb.njit(cache=True)
def _pibt_step(
    gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
    prio: np.ndarray, two_r: float, seed: int, t: int, nxt: np.ndarray,
    cand: np.ndarray, ncand: np.ndarray, ci: np.ndarray, status: np.ndarray,
    stack: np.ndarray, mode: np.ndarray,
) -> None:
    """One PIBT step (priority inheritance with backtracking), iterative.

    Continuous-space addition (*yield*): a robot that inherited priority and found no
    move compatible with its ancestors' intended motions scans its candidates again
    checking only the ancestors' current positions. A move found that way clears the way
    for the next step while the ancestor, which re-checks against it, waits or detours.
    Without it two robots 10 cm apart whose simultaneous moves would graze each other
    could block each other forever (the parent's wait always beating its detours).
    """
    coords = gr[0]
    N = cur.shape[0]
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
        _build_cands(r0, cur[r0], gr, V, gv0, hs, goal, seed, t, cand, ncand)
        ci[r0] = 0
        stack[0] = r0
        sp = 1
        while sp > 0:
            i = stack[sp - 1]
            if ci[i] >= ncand[i]:
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
            ax = coords[cur[i], 0]
            ay = coords[cur[i], 1]
            bx = coords[c, 0]
            by = coords[c, 1]
            c_goal = c >= gv0
            bad = False
            blocker = -1
            for k in range(N):
                if k == i:
                    continue
                sk = status[k]
                px = coords[cur[k], 0]
                py = coords[cur[k], 1]
                stay_goal = c_goal and cur[k] >= gv0
                if sk == _UNDECIDED:
                    if blocker < 0 and _conflict(ax, ay, bx, by, px, py, px, py, two_r,
                                                 stay_goal):
                        blocker = k
                elif sk == _DECIDED:
                    qx = coords[nxt[k], 0]
                    qy = coords[nxt[k], 1]
                    if _conflict(ax, ay, bx, by, px, py, qx, qy, two_r,
                                 c_goal and nxt[k] >= gv0):
                        bad = True
                        break
                else:  # tentative ancestor: its position now and its intended motion
                    qx = coords[nxt[k], 0]
                    qy = coords[nxt[k], 1]
                    if _conflict(ax, ay, bx, by, px, py, px, py, two_r, stay_goal) or (
                        mode[i] == 0
                        and _conflict(ax, ay, bx, by, px, py, qx, qy, two_r,
                                      c_goal and nxt[k] >= gv0)
                    ):
                        bad = True
                        break
            if bad:
                ci[i] += 1
                continue
            if blocker >= 0:
                # priority inheritance: the blocker decides first, then i re-checks c
                status[blocker] = _TENTATIVE
                _build_cands(blocker, cur[blocker], gr, V, gv0, hs, goal, seed, t, cand, ncand)
                ci[blocker] = 0
                mode[blocker] = 0
                stack[sp] = blocker
                sp += 1
                continue
            status[i] = _DECIDED
            sp -= 1


@nb.njit(cache=True)
def _swap_goals(gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
                prio: np.ndarray) -> int:
    """Pairwise goal swaps that lower the summed heuristic (priorities travel along)."""
    N = cur.shape[0]
    nswap = 0
    for i in range(N):
        for j in range(i + 1, N):
            gi = goal[i]
            gj = goal[j]
            if gi < 0 and gj < 0:
                continue
            now = 0.0
            sw = 0.0
            if gi >= 0:
                now += _hval(gi, cur[i], gr, V, gv0, hs)
                sw += _hval(gi, cur[j], gr, V, gv0, hs)
            if gj >= 0:
                now += _hval(gj, cur[j], gr, V, gv0, hs)
                sw += _hval(gj, cur[i], gr, V, gv0, hs)
            if sw < now - 1e-9:
                goal[i] = gj
                goal[j] = gi
                p = prio[i]
                prio[i] = prio[j]
                prio[j] = p
                nswap += 1
    return nswap


@nb.njit(cache=True)
def run_steps(
    gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
    prio: np.ndarray, two_r: float, seed: int, swap: bool, hist: np.ndarray,
    hsum: np.ndarray, t0: int, t1: int, maxc: int,
) -> tuple[int, bool]:
    """Run Gspi steps t0..t1-1; hist[t+1] receives the vertices after step t and
    hsum[t+1] the summed heuristic. Returns (rows filled - 1, all goals reached)."""
    N = cur.shape[0]
    nxt = np.empty(N, dtype=np.int64)
    cand = np.empty((N, maxc), dtype=np.int64)
    ncand = np.zeros(N, dtype=np.int64)
    ci = np.zeros(N, dtype=np.int64)
    status = np.zeros(N, dtype=np.int64)
    stack = np.empty(N, dtype=np.int64)
    mode = np.zeros(N, dtype=np.int64)
    for t in range(t0, t1):
        done = True
        for i in range(N):
            if goal[i] >= 0 and cur[i] != gv0 + goal[i]:
                done = False
                break
        if done:
            return t, True
        if swap:
            _swap_goals(gr, V, gv0, hs, cur, goal, prio)
        _pibt_step(gr, V, gv0, hs, cur, goal, prio, two_r, seed, t, nxt, cand, ncand, ci,
                   status, stack, mode)
        s = 0.0
        for i in range(N):
            cur[i] = nxt[i]
            hist[t + 1, i] = nxt[i]
            g = goal[i]
            if g < 0 or cur[i] == gv0 + g:
                prio[i] = prio[i] - math.floor(prio[i])
            else:
                prio[i] += 1.0
                s += min(_hval(g, cur[i], gr, V, gv0, hs), 1e6)
        hsum[t + 1] = s
    done = True
    for i in range(N):
        if goal[i] >= 0 and cur[i] != gv0 + goal[i]:
            done = False
            break
    return t1, done


@nb.njit(cache=True)
def start_costs(gr: tuple, V: int, gv0: int, hs: tuple, N: int, m: int) -> np.ndarray:
    """(N,) heuristic distance from each start vertex to goal m."""
    C = np.empty(N)
    for i in range(N):
        C[i] = _hval(m, V + i, gr, V, gv0, hs)
    return C
