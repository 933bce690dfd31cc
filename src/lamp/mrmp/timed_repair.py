"""Repair of a retimed fleet plan: the robots that arrive last are planned again in time.

After the retiming (:mod:`lamp.mrmp.retime`) every robot moves at its own speed, but it
keeps the order in which the synchronised plan let two robots pass the same place: a robot
that waited there for another waits in the retimed plan too, however early it could have
passed. At 800 robots on a 9.6 m map such waits and slow moves made up 0.1-0.5 m of the
last robot's arrival. :func:`timed_repair` plans the robot that arrives last again,
against every other robot's retimed motion as it is, in continuous time, and keeps the
new way when it arrives earlier; then the next last robot, until the last one cannot
arrive earlier or the work bound is spent.

Search: A* over (vertex, time) of the plan's graph (lattice nodes, the robot's own start
and goal vertices' links, other goals' vertices; never another robot's start vertex) and
knight moves between lattice nodes whose segment keeps the space's clearance (16
directions: ways closer to the straight line than the lattice's),
time in whole quanta ``q`` (the retiming's): a move along an edge lasts
``ceil(length / q)`` quanta (unit speed at most), a wait :data:`TIMED_WAIT` quanta; a
state is kept once per (vertex, time) and pruned when its time plus the exact lattice
distance to the goal (in quanta, :data:`OCTILE`) is not below the target (the old
arrival, less one quantum). The goal is reached once the robot may stay there to the end.

Why the plan stays valid: the graph's edges are the obstacle-checked lattice edges and
links; every move and wait of the new way is checked against the motion of every other
robot in each row it overlaps, cut at the rows' times (both linear there, so the check is
exact), with Gspi's rule (:func:`lamp.mrmp.gspi_kernels.conflict`: the distance never
falls below ``min(2r, distance at the piece's start)``, two robots ending on goals
excepted), and so is the stay on the goal to the end. The other robots' rows are
unchanged; new rows are only inserted at the new way's times (the other robots move
linearly between rows, so their positions there are exact), and every robot still moves
at most ``max_spacing`` between rows. Deterministic: bounded by a count of states.

Other robots are found through a spatial hash of the rows (:mod:`lamp.mrmp.repair_hash`),
cells wider than ``2r`` plus the longest distance two robots move within a piece.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.goal_distances import hval
from lamp.mrmp.heuristic_reads import goal_views, read_in
from lamp.mrmp.neighbours import doubled
from lamp.mrmp.obstacle_grid import grid_clear_segments
from lamp.mrmp.repair_hash import hash_rows
from lamp.mrmp.timed_checks import arrivals, free_time, motion_clear, with_way

__all__ = ["KNIGHT", "OCTILE", "TIMED_BUDGET", "TIMED_ENTRIES", "TIMED_ROUNDS", "TIMED_WAIT",
           "timed_repair"]

#: States all the searches of one call may expand together (the work bound).
TIMED_BUDGET = 5000
#: The most robots planned again in one call.
TIMED_ROUNDS = 24
#: Plans of more rows times robots are left as they are: the rows' hash and the
#: searches' checks grow with them (a 1,600-robot plan on ``den520d``, 1.4-1.9 million,
#: took 0.15-0.35 s for a few hundredths of a metre).
TIMED_ENTRIES = 1_000_000
#: Quanta of one wait action.
TIMED_WAIT = 2
#: The knight moves of the search (lattice index offsets): with the 8 lattice directions,
#: 16 directions, a way at most 2.7 % longer than the straight line where nothing is in
#: the way (8 % on the lattice alone).
KNIGHT = np.array([[1, 2], [2, 1], [2, -1], [1, -2], [-1, -2], [-2, -1], [-2, 1], [-1, 2]],
                  dtype=np.int64)
#: The search's heuristic is the lattice distance over this. 1: with knight moves it is
#: no lower bound (an 8-direction way is up to 1 / cos 22.5 deg = 1.0824 times the
#: straight line), so the search finds an earlier way, not always the earliest; 1.0824
#: makes it a lower bound, for about twice the states and no shorter plans measured.
OCTILE = 1.0


@nb.njit(cache=True, inline="always")
def _push(hf: np.ndarray, ht: np.ndarray, hi: np.ndarray, n: int, f: float, t: int,
          idx: int) -> None:
    """Binary min-heap on (f, -t): the latest state first among equal f."""
    c = n
    while c > 0:
        p = (c - 1) // 2
        if hf[p] < f or (hf[p] == f and ht[p] >= t):
            break
        hf[c], ht[c], hi[c] = hf[p], ht[p], hi[p]
        c = p
    hf[c], ht[c], hi[c] = f, t, idx


@nb.njit(cache=True, inline="always")
def _pop(hf: np.ndarray, ht: np.ndarray, hi: np.ndarray, n: int) -> int:
    """Remove the heap's top (``n`` entries before); returns its state index."""
    top = hi[0]
    n -= 1
    f, t, idx = hf[n], ht[n], hi[n]
    c = 0
    while True:
        a = 2 * c + 1
        if a >= n:
            break
        b = a + 1
        if b < n and (hf[b] < hf[a] or (hf[b] == hf[a] and ht[b] > ht[a])):
            a = b
        if f < hf[a] or (f == hf[a] and t >= ht[a]):
            break
        hf[c], ht[c], hi[c] = hf[a], ht[a], hi[a]
        c = a
    hf[c], ht[c], hi[c] = f, t, idx
    return top


@nb.njit(cache=True)
def _knight(v: int, k: int, va: np.ndarray, vb: np.ndarray, ids: np.ndarray,
            coords: np.ndarray, kclear: dict, ob: tuple) -> int:
    """Lattice node v's knight neighbour k (0..7; :data:`KNIGHT`) when the segment to it
    keeps the clearance ``ob[0]`` from the obstacles (exact; answers kept in
    ``kclear``), else -1."""
    a = va[v] + KNIGHT[k, 0]
    b = vb[v] + KNIGHT[k, 1]
    if not (0 <= b < ids.shape[0] and 0 <= a < ids.shape[1]) or ids[b, a] < 0:
        return -1
    u = ids[b, a]
    kk = v * 8 + k
    if kk not in kclear:
        need, circles, verts, vptr, W, H, gptr, gidx, box, gnx, gny, gcell = ob
        sa = np.empty((1, 2))
        sb = np.empty((1, 2))
        sa[0, 0], sa[0, 1] = coords[v, 0], coords[v, 1]
        sb[0, 0], sb[0, 1] = coords[u, 0], coords[u, 1]
        kclear[kk] = grid_clear_segments(sa, sb, need, circles, verts, vptr, W, H, gptr,
                                         gidx, box, gnx, gny, gcell)[0]
    return u if kclear[kk] else -1


@nb.njit(cache=True)
def _search(i: int, m: int, gr: tuple, V: int, gv0: int, hs: tuple, X: np.ndarray,
            Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
            ny: int, two_r: float, ends_goal: np.ndarray, q: float, target: int,
            budget: int, ob: tuple, ways: tuple) -> tuple[np.ndarray, np.ndarray, int]:
    """Robot i's earliest way to goal m arriving before ``target`` quanta (module
    docstring): its vertices and their times in quanta (empty when none), and the
    states expanded. Knight moves between lattice nodes (:data:`KNIGHT`) are taken when
    their segment keeps the clearance ``ob[0]`` (exact; ``ob``: the obstacles' grid)."""
    coords, nbr, _, xptr, xidx = gr
    va, vb, ids, sdone, sval = hs[11], hs[12], hs[13], hs[9], hs[10]
    kclear = dict()  # knight moves checked: (v * 8 + k) -> clear
    kclear[0] = True
    del kclear[0]
    g = gv0 + m
    gx, gy = coords[g, 0], coords[g, 1]
    none = np.zeros(0, np.int64)
    free = free_time(i, gx, gy, X, Y, tt, hh, x0, y0, cs, ny, two_r, ends_goal, ways)
    if not free < target * q:
        return none, none, 0
    dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
    cap = 1 << 12
    sv = np.empty(cap, np.int64)
    st = np.empty(cap, np.int64)
    sp = np.empty(cap, np.int64)
    hf = np.empty(cap)
    ht = np.empty(cap, np.int64)
    hi = np.empty(cap, np.int64)
    seen = dict()
    seen[0] = 0
    del seen[0]
    v0 = V + i
    sv[0], st[0], sp[0] = v0, 0, -1
    n = 1
    nh = 0
    _push(hf, ht, hi, nh, 0.0, 0, 0)
    nh = 1
    span_t = np.int64(target) + 1
    work = 0
    found = -1
    while nh > 0 and work < budget:
        s = _pop(hf, ht, hi, nh)
        nh -= 1
        v = sv[s]
        t = st[s]
        if v == g and t * q >= free:
            found = s
            break
        work += 1
        ax, ay = coords[v, 0], coords[v, 1]
        deg = 1 + (8 if v < V else 0) + (xptr[v + 1] - xptr[v])
        for e in range(deg + (8 if v < V else 0)):
            if e == 0:
                u = v
            elif v < V and e <= 8:
                u = nbr[v, e - 1]
            elif e >= deg:
                u = _knight(v, e - deg, va, vb, ids, coords, kclear, ob)
            else:
                u = xidx[xptr[v] + e - 1 - (8 if v < V else 0)]
                if V <= u < gv0:
                    u = -1
            if u < 0:
                continue
            bx, by = coords[u, 0], coords[u, 1]
            d = TIMED_WAIT if u == v else int(math.ceil(math.hypot(bx - ax, by - ay) / q
                                                            - 1e-9))
            t2 = t + d
            if t2 >= target:
                continue
            key = u * span_t + t2
            if key in seen:
                continue
            hu = read_in(m, u, V, va, vb, sdone, sval, dd, dn, wa0, wb0, wna, wnb)
            if hu < 0.0:
                hu = hval(m, u, gr, V, gv0, hs)
                dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
            f = t2 + hu / (q * OCTILE)
            if not f < target - 1e-6:
                continue
            if not motion_clear(i, ax, ay, bx, by, t * q, t2 * q, u == g, X, Y, tt, hh,
                                x0, y0, cs, ny, two_r, ends_goal, ways):
                continue
            seen[key] = n
            if n == sv.shape[0]:
                sv, st, sp = doubled(sv, n), doubled(st, n), doubled(sp, n)
            if nh == hf.shape[0]:
                hf, ht, hi = doubled(hf, nh), doubled(ht, nh), doubled(hi, nh)
            sv[n], st[n], sp[n] = u, t2, s
            _push(hf, ht, hi, nh, f, t2, n)
            nh += 1
            n += 1
    if found < 0:
        return none, none, work
    pv, pt = _unwind(found, sv, st, sp)
    return pv, pt, work


@nb.njit(cache=True)
def _unwind(found: int, sv: np.ndarray, st: np.ndarray, sp: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """The vertices and times of the states from the first to ``found`` (parents
    ``sp``)."""
    c = 0
    s = found
    while s >= 0:
        c += 1
        s = sp[s]
    pv = np.empty(c, np.int64)
    pt = np.empty(c, np.int64)
    s = found
    for k in range(c - 1, -1, -1):
        pv[k] = sv[s]
        pt[k] = st[s]
        s = sp[s]
    return pv, pt


@nb.njit(cache=True)
def _rounds(X: np.ndarray, Y: np.ndarray, tt: np.ndarray, gr: tuple, V: int, gv0: int,
            hs: tuple, goal: np.ndarray, two_r: float, q: float, cs: float,
            max_spacing: float, budget: int, rounds: int, ob: tuple
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
    """The loop of :func:`timed_repair` on the rows ``X, Y`` (times ``tt``, metres):
    (rows, times, robots planned again, states expanded). The rows and their hash are
    kept while the new ways are found (each checked against the ways found before it),
    and the ways are written into the rows at the end."""
    coords = gr[0]
    N = X.shape[1]
    x0, y0 = coords[:, 0].min(), coords[:, 1].min()
    x1, y1 = coords[:, 0].max(), coords[:, 1].max()
    ends_goal = goal >= 0
    arr = arrivals(X, Y, tt)
    hh, ny = hash_rows(X, Y, x0, y0, x1, y1, cs, True)
    rep = np.zeros(N, np.bool_)
    WX = np.empty(256)
    WY = np.empty(256)
    WT = np.empty(256)
    wptr = np.zeros(rounds + 1, np.int64)
    wrob = np.full(rounds, -1, np.int64)
    box = np.empty((rounds, 4))
    nw = 0
    work = 0
    for _ in range(rounds):
        if work >= budget or tt.shape[0] < 2:
            break
        i = int(np.argmax(arr))
        if goal[i] < 0:
            break
        target = int(math.ceil(arr[i] / q - 1e-9))
        ways = (rep, WX, WY, WT, wptr[: nw + 1], wrob[:nw], box[:nw])
        pv, pt, w = _search(i, goal[i], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs, ny,
                            two_r, ends_goal, q, target, budget - work, ob, ways)
        work += w
        if pv.shape[0] == 0:
            break
        for u in range(nw):
            if wrob[u] == i:
                wrob[u] = -1
        p0 = wptr[nw]
        while p0 + pv.shape[0] > WX.shape[0]:
            WX, WY, WT = doubled(WX, p0), doubled(WY, p0), doubled(WT, p0)
        for k in range(pv.shape[0]):
            WX[p0 + k], WY[p0 + k] = coords[pv[k], 0], coords[pv[k], 1]
            WT[p0 + k] = pt[k] * q
        wptr[nw + 1] = p0 + pv.shape[0]
        wrob[nw] = i
        box[nw, 0] = WX[p0: p0 + pv.shape[0]].min()
        box[nw, 1] = WX[p0: p0 + pv.shape[0]].max()
        box[nw, 2] = WY[p0: p0 + pv.shape[0]].min()
        box[nw, 3] = WY[p0: p0 + pv.shape[0]].max()
        rep[i] = True
        arr[i] = WT[p0 + pv.shape[0] - 1]
        nw += 1
    for u in range(nw):
        if wrob[u] >= 0:
            a, b = wptr[u], wptr[u + 1]
            X, Y, tt = with_way(X, Y, tt, wrob[u], WX[a:b], WY[a:b], WT[a:b], max_spacing)
    return X, Y, tt, nw, work


def timed_repair(rows: np.ndarray, times: np.ndarray, gr: tuple, V: int, gv0: int,
                 hs: tuple, goal: np.ndarray, two_r: float, quantum: float,
                 max_move: float, max_spacing: float, geometry, workspace: tuple[float, float],
                 need: float, budget: int = TIMED_BUDGET, rounds: int = TIMED_ROUNDS
                 ) -> tuple[np.ndarray, int, int]:
    """The retimed ``rows`` ((N, R, 2), at ``times``, metres at unit speed) with their
    last robots planned again in time (module docstring) over the graph ``gr`` (goal
    distances ``hs``, robot i's start vertex ``V + i``, goal m's ``gv0 + m``);
    ``quantum``: the time step of the new ways (metres), ``max_move``: the graph's
    longest edge; ``geometry``, ``workspace``, ``need``: the obstacles, the workspace and
    the clearance a knight move keeps (the space's threshold). Plans of more than
    :data:`TIMED_ENTRIES` rows times robots are returned as they are. Returns the rows, the
    robots planned again and the states expanded."""
    from lamp.mrmp.obstacle_grid import get_grid

    rows = np.asarray(rows, dtype=np.float64)
    if rows.shape[0] < 2 or rows.shape[1] < 2 or rows.shape[0] * rows.shape[1] > TIMED_ENTRIES:
        return rows, 0, 0
    X = np.ascontiguousarray(rows[:, :, 0].T)
    Y = np.ascontiguousarray(rows[:, :, 1].T)
    # a knight move is at most sqrt(5) / sqrt(2) times the longest lattice edge
    longest = max(max_move, 1.6 * max_move, max_spacing)
    cs = two_r + longest + 2.0 * max_spacing + 1e-6
    g = get_grid(geometry)
    W, H = workspace
    ob = (np.full(1, float(need)), geometry.circles, geometry.verts, geometry.ptr, float(W),
          float(H), g.ptr, g.idx, g.box, g.nx, g.ny, g.cell)
    X, Y, _, done, work = _rounds(X, Y, np.asarray(times, np.float64), gr, V, gv0, hs,
                                  np.asarray(goal, np.int64), float(two_r), float(quantum),
                                  cs, float(max_spacing), int(budget), int(rounds), ob)
    return np.ascontiguousarray(np.stack([X.T, Y.T], axis=2)), done, work
