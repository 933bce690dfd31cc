"""Repair of a synchronised Gspi plan: the robots that arrive last are planned again.

Gspi decides each step for all robots at once, greedily; a robot may be pushed off its
goal by robots passing by, or wander while goals are swapped around it, and arrive long
after the others. :func:`repair_last` lowers the latest *arrival estimate* of the plan,
over and over: a robot's estimate is the summed length of its moves plus ``wait_cost``
per step it waits, up to its last move (what its arrival will be once every robot moves
at its own speed, :func:`lamp.mrmp.retime.retime`, give or take the waits). The robot
with the largest estimate is planned again, the others' motions fixed: the cheapest way
to its goal over the same graph and synchronised steps, cheaper than now. When there is
none, the robots in the way of its cheapest way with nobody else around are planned again
after it, as a group (at most ``max_group`` of them, each cheaper than the old largest
estimate); when that fails too, it exchanges goals with the holder of a goal nearer to
its start (the ``n_exchange`` nearest candidates), both and the robots in their ways
planned again. It stops when the robot with the largest estimate cannot be improved, or
after ``budget`` searched states.

Why the plan stays valid: every new motion, and every wait, is checked against the motion
of every robot not being planned again in that step with the rule Gspi itself applies
(:func:`lamp.mrmp.gspi_kernels.conflict`), and so is the stay on the goal afterwards; a
group replaces its old paths only when all its members succeeded; graph edges are the
checked lattice edges and links. Deterministic: the order is fixed, and the work is
bounded by a count of states, not by the clock.

Search: a dynamic programme over (vertex, step) pairs, layer by layer of steps, each
vertex kept once per step at its least cost; a state is pruned when its cost plus the
exact lattice distance to the goal is not below the best found (or the target). Other
robots are found through a spatial hash of their positions at each step (cells wider
than the distance within which two robots can conflict in one step); rows are added
after the last (half as many) so that paths of more, shorter steps fit.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.borrow import borrowed
from lamp.mrmp.goal_distances import hval
from lamp.mrmp.heuristic_reads import goal_views, read_in
from lamp.mrmp.neighbours import doubled
from lamp.mrmp.repair_hash import build_hash, cell, clear_of, gather, move_ok, set_key

__all__ = ["REPAIR_BUDGET", "REPAIR_EXCHANGES", "REPAIR_GROUP", "REPAIR_WAIT", "arrival_estimates",
           "repair_last"]

#: States a call may expand in all (the work bound; not the clock, for determinism).
REPAIR_BUDGET = 200_000
#: The most robots planned again together with the last one (those in its way).
REPAIR_GROUP = 8
#: Goal exchanges tried for the last robot when its own goal cannot be reached sooner.
REPAIR_EXCHANGES = 8
#: Cost of a wait in the arrival estimate, in lattice steps (retiming may shorten it).
REPAIR_WAIT = 1.0


@nb.njit(cache=True)
def _arrival(VX: np.ndarray, i: int) -> int:
    """The first row from which robot i no longer moves."""
    K1 = VX.shape[0]
    a = K1 - 1
    while a > 0 and VX[a - 1, i] == VX[K1 - 1, i]:
        a -= 1
    return a


@nb.njit(cache=True, inline="always")
def _successor(v: int, e: int, V: int, gv0: int, nbr: np.ndarray, xptr: np.ndarray,
               xidx: np.ndarray) -> int:
    """Successor ``e`` of vertex v (0: v itself, then its lattice neighbours, then its
    extra edges), or -1 (no such neighbour; another robot's start, never entered)."""
    if e == 0:
        return v
    if v < V:
        if e <= 8:
            return nbr[v, e - 1]
        e -= 8
    u = xidx[xptr[v] + e - 1]
    return -1 if V <= u < gv0 else u


@nb.njit(cache=True)
def _cost(VX: np.ndarray, i: int, coords: np.ndarray, wait_cost: float) -> float:
    """Robot i's arrival under the proxy: its moves' lengths and ``wait_cost`` per step
    it waits before its last move."""
    a = _arrival(VX, i)
    c = 0.0
    for t in range(a):
        u = VX[t, i]
        w = VX[t + 1, i]
        if u == w:
            c += wait_cost
        else:
            c += math.hypot(coords[w, 0] - coords[u, 0], coords[w, 1] - coords[u, 1])
    return c


@nb.njit(cache=True)
def _free_from(i: int, g: int, VX: np.ndarray, coords: np.ndarray, gv0: int, hh: tuple,
               x0: float, y0: float, cs: float, ny: int, two_r: float,
               skip: np.ndarray) -> int:
    """The first row from which robot i may stay on its goal vertex g to the end."""
    none = np.zeros(0, np.bool_)
    for s in range(VX.shape[0] - 2, -1, -1):
        if not move_ok(i, s, g, g, VX, coords, gv0, hh, x0, y0, cs, ny, two_r, skip, none):
            return s + 1
    return 0


@nb.njit(cache=True)
def _search(i: int, target: float, gr: tuple, V: int, gv0: int, hs: tuple, goal: np.ndarray,
            VX: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
            ny: int, two_r: float, wait_cost: float, mark: np.ndarray, pos: np.ndarray,
            stamp: int, budget: int, out: np.ndarray, skip: np.ndarray
            ) -> tuple[int, float, int]:
    """The cheapest way of robot i to its goal under the arrival proxy (moves' lengths,
    ``wait_cost`` per wait), cheaper than ``target``, within the rows of ``VX``, the robots
    not in ``skip`` fixed: (arrival row or -1, its cost, states expanded); its vertices
    per row in ``out[:arrival + 1]``. Arguments borrowed (:mod:`lamp.mrmp.borrow`)."""
    gr, hs, goal, VX, hh, mark, pos, out, skip = borrowed(
        (gr, hs, goal, VX, hh, mark, pos, out, skip))
    coords, nbr, _, xptr, xidx = gr
    K1 = VX.shape[0]
    m = goal[i]
    g = gv0 + m
    free = _free_from(i, g, VX, coords, gv0, hh, x0, y0, cs, ny, two_r, skip)
    dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)  # goal m's window (read_in)
    va, vb, sdone, sval = hs[11], hs[12], hs[9], hs[10]  # read once: no counts per read
    cap = 1 << 14
    lv = np.empty(cap, np.int64)
    lp = np.empty(cap, np.int64)
    lc = np.empty(cap)
    lstart = np.zeros(K1 + 1, np.int64)
    lv[0] = VX[0, i]
    lp[0] = -1
    lc[0] = 0.0
    n = 1
    lstart[1] = 1
    work = 0
    best = target
    best_q = -1
    best_t = -1
    reach = two_r + 0.5 * (cs - two_r) + 1e-6  # moves are <= (cs - 2r) / 2 (gather)
    buf = np.empty((VX.shape[1], 5))
    if VX[0, i] == g and free == 0:
        best_q, best_t, best = 0, 0, 0.0
    for t in range(K1 - 1):
        a0 = lstart[t]
        a1 = lstart[t + 1]
        if a0 == a1:
            break
        for q in range(a0, a1):
            v = lv[q]
            cv = lc[q]
            nn = -1
            work += 1
            if work > budget:
                return -1, 0.0, work
            for e in range(1 + (8 if v < V else 0) + (xptr[v + 1] - xptr[v])):
                u = _successor(v, e, V, gv0, nbr, xptr, xidx)
                if u < 0:
                    continue
                if u == v:
                    nc = cv + (0.0 if v == g else wait_cost)
                else:
                    nc = cv + math.hypot(coords[u, 0] - coords[v, 0],
                                         coords[u, 1] - coords[v, 1])
                if mark[u] == stamp + t + 1 and lc[pos[u]] <= nc:
                    continue
                hu = read_in(m, u, V, va, vb, sdone, sval, dd, dn, wa0, wb0, wna, wnb)
                if hu < 0.0:
                    hu = hval(m, u, gr, V, gv0, hs)
                    dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
                if not nc + hu < best - 1e-9:
                    continue
                if nn < 0:
                    nn = gather(i, t, v, VX, coords, gv0, hh, x0, y0, cs, ny, reach, skip,
                                buf)
                if not clear_of(coords[v, 0], coords[v, 1], coords[u, 0], coords[u, 1],
                                u >= gv0, buf, nn, two_r):
                    continue
                if mark[u] == stamp + t + 1:
                    r = pos[u]
                    lc[r] = nc
                    lp[r] = q
                else:
                    mark[u] = stamp + t + 1
                    if n == lv.shape[0]:
                        lv = doubled(lv, n)
                        lp = doubled(lp, n)
                        lc = doubled(lc, n)
                    lv[n] = u
                    lp[n] = q
                    lc[n] = nc
                    pos[u] = n
                    r = n
                    n += 1
                if u == g and t + 1 >= free and nc < best:
                    best = nc
                    best_q = r
                    best_t = t + 1
        lstart[t + 2] = n
    if best_q < 0:
        return -1, 0.0, work
    # unwind (the entries of the goal's layer may have been improved since: re-read)
    r = best_q
    for s in range(best_t, -1, -1):
        out[s] = lv[r]
        r = lp[r]
    return best_t, lc[best_q], work


@nb.njit(cache=True)
def _write(i: int, path: np.ndarray, a: int, K: int, VX: np.ndarray, coords: np.ndarray,
           hh: tuple, x0: float, y0: float, cs: float, ny: int) -> None:
    """Robot i's rows 0..K become ``path[:a + 1]`` then its last vertex (hash kept)."""
    for t in range(K + 1):
        v = path[t] if t <= a else path[a]
        if v != VX[t, i]:
            VX[t, i] = v
            set_key(t, i, cell(coords[v, 0], coords[v, 1], x0, y0, cs, ny), hh)


@nb.njit(cache=True)
def _blockers(i: int, path: np.ndarray, a: int, K: int, VX: np.ndarray, coords: np.ndarray,
              gv0: int, hh: tuple, x0: float, y0: float, cs: float,
              ny: int, two_r: float, skip: np.ndarray) -> np.ndarray:
    """The robots whose motions conflict with robot i following ``path`` (arrival ``a``,
    then staying) up to row K."""
    found = np.zeros(VX.shape[1], np.bool_)
    for t in range(K):
        u = path[t] if t <= a else path[a]
        w = path[t + 1] if t + 1 <= a else path[a]
        move_ok(i, t, u, w, VX, coords, gv0, hh, x0, y0, cs, ny, two_r, skip, found)
    return np.nonzero(found)[0]


@nb.njit(cache=True)
def _group(members: np.ndarray, target: float, gr: tuple, V: int, gv0: int, hs: tuple,
           goal: np.ndarray, VX: np.ndarray, hh: tuple, x0: float,
           y0: float, cs: float, ny: int, two_r: float, wait_cost: float, mark: np.ndarray,
           pos: np.ndarray, stamp: int, budget: int, out: np.ndarray, skip: np.ndarray,
           old: np.ndarray, newc: np.ndarray) -> tuple[bool, int, int]:
    """Plan ``members`` again in turn, each cheaper than ``target``, the later ones not
    yet planned ignored by the earlier; on a failure every member's rows are restored.
    Returns (success, states expanded, stamp)."""
    coords = gr[0]
    K = VX.shape[0] - 1
    nm = members.shape[0]
    for q in range(nm):
        old[:, q] = VX[:, members[q]]
        skip[members[q]] = True
    done = 0
    work = 0
    for q in range(nm):
        r = members[q]
        skip[r] = False
        a, c, w = _search(r, target, gr, V, gv0, hs, goal, VX, hh, x0, y0, cs, ny,
                          two_r, wait_cost, mark, pos, stamp, budget - work, out, skip)
        work += w
        stamp += K + 3
        if a < 0:
            break
        _write(r, out, a, K, VX, coords, hh, x0, y0, cs, ny)
        newc[q] = c
        done += 1
    for q in range(nm):
        skip[members[q]] = False
    if done < nm:
        for q in range(nm):
            _write(members[q], old[:, q], K, K, VX, coords, hh, x0, y0, cs, ny)
        return False, work, stamp
    return True, work, stamp


@nb.njit(cache=True)
def _with_blockers(first: np.ndarray, target: float, gr: tuple, V: int, gv0: int, hs: tuple,
                   goal: np.ndarray, VX: np.ndarray, hh: tuple,
                   x0: float, y0: float, cs: float, ny: int, two_r: float, wait_cost: float,
                   mark: np.ndarray, pos: np.ndarray, stamp: int, budget: int,
                   out: np.ndarray, skip: np.ndarray, every: np.ndarray, old: np.ndarray,
                   newc: np.ndarray, max_group: int
                   ) -> tuple[bool, np.ndarray, int, int]:
    """``first`` and the robots in the way of their cheapest ways (others ignored),
    planned again as a group (:func:`_group`). Returns (success, members, work, stamp)."""
    coords = gr[0]
    K = VX.shape[0] - 1
    N = VX.shape[1]
    work = 0
    inway = np.zeros(N, np.bool_)
    for q in range(first.shape[0]):
        r = first[q]
        a, c, w = _search(r, target, gr, V, gv0, hs, goal, VX, hh, x0, y0, cs, ny,
                          two_r, wait_cost, mark, pos, stamp, budget - work, out, every)
        work += w
        stamp += K + 3
        if a < 0:
            return False, first, work, stamp
        for b in _blockers(r, out, a, K, VX, coords, gv0, hh, x0, y0, cs, ny, two_r,
                           skip):
            inway[b] = True
    for q in range(first.shape[0]):
        inway[first[q]] = False
    grp = np.nonzero(inway)[0]
    if grp.shape[0] > max_group:
        return False, first, work, stamp
    for b in grp:
        if goal[b] < 0:
            return False, first, work, stamp
    members = np.empty(first.shape[0] + grp.shape[0], np.int64)
    members[: first.shape[0]] = first
    members[first.shape[0]:] = grp
    ok, w, stamp = _group(members, target, gr, V, gv0, hs, goal, VX, hh, x0, y0, cs, ny,
                          two_r, wait_cost, mark, pos, stamp, budget - work, out, skip, old,
                          newc)
    return ok, members, work + w, stamp


@nb.njit(cache=True)
def _exchange(i: int, target: float, gr: tuple, V: int, gv0: int, hs: tuple,
              goal: np.ndarray, holder: np.ndarray, VX: np.ndarray, hh: tuple, x0: float,
              y0: float, cs: float, ny: int, two_r: float,
              wait_cost: float, mark: np.ndarray, pos: np.ndarray, stamp: int, budget: int,
              out: np.ndarray, skip: np.ndarray, every: np.ndarray, old: np.ndarray,
              newc: np.ndarray, max_group: int, n_exchange: int
              ) -> tuple[bool, np.ndarray, int, int]:
    """Robot i exchanges goals with the holder j of a goal m nearer to i's start, both
    (and the robots in their ways) planned again cheaper than ``target``: candidates by
    the longer of the two straight lines, the first ``n_exchange`` whose exact distances
    from the starts are below the target tried in turn. ``goal`` and ``holder`` change
    only on success. Returns (success, members, work, stamp)."""
    coords = gr[0]
    gi = goal[i]
    M = holder.shape[0]
    key = np.full(M, np.inf)
    for m in range(M):
        j = holder[m]
        if j < 0 or j == i:
            continue
        d1 = math.hypot(coords[gv0 + m, 0] - coords[V + i, 0],
                        coords[gv0 + m, 1] - coords[V + i, 1])
        d2 = math.hypot(coords[gv0 + gi, 0] - coords[V + j, 0],
                        coords[gv0 + gi, 1] - coords[V + j, 1])
        if d1 < target and d2 < target:
            key[m] = max(d1, d2)
    two = np.empty(2, np.int64)
    tried = 0
    work = 0
    for m in np.argsort(key):
        if tried >= n_exchange or work >= budget or key[m] == np.inf:
            break
        j = holder[m]
        if (hval(m, V + i, gr, V, gv0, hs) >= target
                or hval(gi, V + j, gr, V, gv0, hs) >= target):
            continue
        tried += 1
        goal[i] = m
        goal[j] = gi
        two[0] = i
        two[1] = j
        ok, members, w, stamp = _with_blockers(
            two, target, gr, V, gv0, hs, goal, VX, hh, x0, y0, cs, ny, two_r, wait_cost,
            mark, pos, stamp, budget - work, out, skip, every, old, newc, max_group)
        work += w
        if ok:
            holder[m] = i
            holder[gi] = j
            return True, members, work, stamp
        goal[i] = gi
        goal[j] = m
    return False, two, work, stamp


@nb.njit(cache=True)
def repair_last(gr: tuple, V: int, gv0: int, hs: tuple, VX: np.ndarray, goal: np.ndarray,
                two_r: float, max_move: float, wait_cost: float, budget: int,
                max_group: int, n_exchange: int) -> tuple[np.ndarray, int, int]:
    """The plan ``VX`` ((K+1, N) vertices per row) with its last robots planned again
    (see the module docstring), trailing rows without motion dropped; ``goal`` updated in
    place where goals were exchanged. Returns the plan, the number of paths replaced and
    the states expanded (at most about ``budget``)."""
    coords = gr[0]
    K0, N = VX.shape
    if K0 < 3 or N < 2:
        return VX.copy(), 0, 0
    K1 = K0 + K0 // 2  # room for paths of more, shorter steps
    VX2 = np.empty((K1, N), np.int64)
    VX2[:K0] = VX
    for t in range(K0, K1):
        VX2[t] = VX[K0 - 1]
    VX = VX2
    cs = two_r + 2.0 * max_move + 1e-6
    hh, x0, y0, ny = build_hash(VX, coords, cs, True)
    cost = np.empty(N)
    for k in range(N):
        cost[k] = _cost(VX, k, coords, wait_cost)
    holder = np.full(coords.shape[0] - gv0, -1, np.int64)
    for k in range(N):
        if goal[k] >= 0:
            holder[goal[k]] = k
    mark = np.full(coords.shape[0], -1, np.int64)
    pos = np.zeros(coords.shape[0], np.int64)
    stamp = 0
    out = np.empty(K1, np.int64)
    old = np.empty((K1, max_group + 2), np.int64)
    newc = np.empty(max_group + 2)
    skip = np.zeros(N, np.bool_)
    every = np.ones(N, np.bool_)
    one = np.empty(1, np.int64)
    work = 0
    replaced = 0
    while work < budget:
        i = int(np.argmax(cost))
        if goal[i] < 0:
            break
        target = cost[i] - 1e-6
        a, c, w = _search(i, target, gr, V, gv0, hs, goal, VX, hh, x0, y0, cs, ny, two_r,
                          wait_cost, mark, pos, stamp, budget - work, out, skip)
        work += w
        stamp += K1 + 2
        if a >= 0:
            _write(i, out, a, K1 - 1, VX, coords, hh, x0, y0, cs, ny)
            cost[i] = c
            replaced += 1
            continue
        one[0] = i
        ok, members, w, stamp = _with_blockers(
            one, target, gr, V, gv0, hs, goal, VX, hh, x0, y0, cs, ny, two_r, wait_cost,
            mark, pos, stamp, budget - work, out, skip, every, old, newc, max_group)
        work += w
        if not ok:
            ok, members, w, stamp = _exchange(
                i, target, gr, V, gv0, hs, goal, holder, VX, hh, x0, y0, cs, ny, two_r,
                wait_cost, mark, pos, stamp, budget - work, out, skip, every, old, newc,
                max_group, n_exchange)
            work += w
        if not ok:
            break
        for q in range(members.shape[0]):
            cost[members[q]] = newc[q]
        replaced += members.shape[0]
    K = 0
    for k in range(N):
        K = max(K, _arrival(VX, k))
    return VX[: K + 1].copy(), replaced, work


@nb.njit(cache=True)
def arrival_estimates(VX: np.ndarray, coords: np.ndarray, wait_cost: float) -> np.ndarray:
    """Every robot's arrival estimate in the rows ``VX`` (:func:`_cost`)."""
    out = np.empty(VX.shape[1])
    for k in range(VX.shape[1]):
        out[k] = _cost(VX, k, coords, wait_cost)
    return out
