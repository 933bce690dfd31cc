"""The search of :mod:`lamp.mrmp.timed_repair`: one robot's earliest way to its goal
against the other robots' retimed motion, over (vertex, time).

A* over (vertex, time) of the plan's graph (lattice nodes, the robot's own start and goal
vertices' links, other goals' vertices; never another robot's start vertex) and knight
moves between lattice nodes whose segment keeps the space's clearance (16 directions:
ways closer to the straight line than the lattice's), time in whole quanta ``q``: a move
along an edge lasts ``ceil(length / q)`` quanta (unit speed at most), a wait
:data:`TIMED_WAIT` quanta; a state is kept once per (vertex, time) and pruned when its
time plus the exact lattice distance to the goal (in quanta, over :data:`OCTILE`, or
:data:`OCTILE_BOUND` where that would prune the ways only knight moves make early
enough) is not below the target. The goal is reached once the robot may stay there to
the end. Every move and wait is checked with
:func:`lamp.mrmp.timed_checks.motion_near` (:func:`~lamp.mrmp.timed_checks.motion_clear`'s
answer), against the robots gathered once per expanded state around its vertex
(:func:`~lamp.mrmp.timed_checks.gather_rows`) rather than looked up in the hash for each
piece of each move.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.borrow import borrowed
from lamp.mrmp.goal_distances import hval
from lamp.mrmp.heuristic_reads import goal_views, read_in
from lamp.mrmp.neighbours import doubled
from lamp.mrmp.obstacle_grid import grid_clear_segments
from lamp.mrmp.timed_checks import free_time, gather_rows, motion_near, rest_clear, row_at

__all__ = ["KNIGHT", "OCTILE", "OCTILE_BOUND", "TIGHT_FROM", "TIMED_WAIT", "heap_pop",
           "heap_push", "move_to", "timed_search"]

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
#: makes it a lower bound, for about twice the states.
OCTILE = 1.0
#: The lower-bound divisor (``tight`` searches): the plain one prunes the ways that only
#: knight moves make early enough, where the robot's lattice distance is near the target
#: (a robot whose shortcut path beats its lattice distance: most of the last robots of an
#: 800-robot fleet).
OCTILE_BOUND = 1.0824
#: :mod:`lamp.mrmp.timed_repair` searches again with the lower bound when the robot's
#: lattice distance is at least this share of the target.
TIGHT_FROM = 0.95


@nb.njit(cache=True, inline="always")
def heap_push(hf: np.ndarray, ht: np.ndarray, hi: np.ndarray, n: int, f: float, t: int,
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
def heap_pop(hf: np.ndarray, ht: np.ndarray, hi: np.ndarray, n: int) -> int:
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


@nb.njit(cache=True, inline="always")
def _slot(tk: np.ndarray, key: int) -> int:
    """The slot of ``key`` in the open-addressing table ``tk`` (length a power of two,
    -1 where empty, linear probing): where it is, else the empty slot it would take."""
    mask = tk.shape[0] - 1
    h = (np.uint64(key) * np.uint64(0x9E3779B97F4A7C15)) >> np.uint64(32)
    j = np.int64(h) & mask
    while tk[j] != key and tk[j] != -1:
        j = (j + 1) & mask
    return j


@nb.njit(cache=True)
def _grown(tk: np.ndarray, tv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The table ``tk`` (keys) / ``tv`` (values) at twice the size, entries moved."""
    nk = np.full(2 * tk.shape[0], -1, np.int64)
    nv = np.empty(2 * tk.shape[0], np.int64)
    for j in range(tk.shape[0]):
        if tk[j] != -1:
            s = _slot(nk, tk[j])
            nk[s] = tk[j]
            nv[s] = tv[j]
    return nk, nv


@nb.njit(cache=True, inline="always")
def _remember(tk: np.ndarray, tv: np.ndarray, nseen: int, slot: int, key: int, s: int
              ) -> tuple[np.ndarray, np.ndarray, int]:
    """Key ``key`` (at ``slot``, from :func:`_slot`) now leads to state ``s``; the table
    (``nseen`` keys) grows to stay at most half full. The table and its key count."""
    if tk[slot] != key:
        nseen += 1
        if 2 * nseen > tk.shape[0]:
            tk, tv = _grown(tk, tv)
            slot = _slot(tk, key)
        tk[slot] = key
    tv[slot] = s
    return tk, tv, nseen


@nb.njit(cache=True, inline="always")
def move_to(e: int, v: int, V: int, gv0: int, deg: int, alone: int, nbr: np.ndarray,
            xptr: np.ndarray, xidx: np.ndarray, va: np.ndarray, vb: np.ndarray,
            ids: np.ndarray, coords: np.ndarray, ob: tuple) -> int:
    """Where move ``e`` from vertex ``v`` leads (-1: nowhere): 0 a wait (none when
    ``alone``: there a wait never arrives earlier), 1-8 the lattice neighbours, then the
    vertex's links (none to another goal), then the knight moves (from ``deg`` on)."""
    if e == 0:
        return -1 if alone > 0 else v
    if v < V and e <= 8:
        return nbr[v, e - 1]
    if e >= deg:
        return _knight(v, e - deg, va, vb, ids, coords, ob)
    u = xidx[xptr[v] + e - 1 - (8 if v < V else 0)]
    return -1 if V <= u < gv0 else u


@nb.njit(cache=True)
def _knight(v: int, k: int, va: np.ndarray, vb: np.ndarray, ids: np.ndarray,
            coords: np.ndarray, ob: tuple) -> int:
    """Lattice node v's knight neighbour k (0..7; :data:`KNIGHT`) when the segment to it
    keeps the clearance ``ob[0]`` from the obstacles (exact), else -1; the answers are
    kept in ``ob[12]`` (entry ``v * 8 + k``: 0 not yet checked, 1 clear, 2 not) for every
    search of the caller."""
    a = va[v] + KNIGHT[k, 0]
    b = vb[v] + KNIGHT[k, 1]
    if not (0 <= b < ids.shape[0] and 0 <= a < ids.shape[1]) or ids[b, a] < 0:
        return -1
    u = ids[b, a]
    need, circles, verts, vptr, W, H, gptr, gidx, box, gnx, gny, gcell, known = ob
    kk = v * 8 + k
    if known[kk] == 0:
        sa = np.empty((1, 2))
        sb = np.empty((1, 2))
        sa[0, 0], sa[0, 1] = coords[v, 0], coords[v, 1]
        sb[0, 0], sb[0, 1] = coords[u, 0], coords[u, 1]
        clear = grid_clear_segments(sa, sb, need, circles, verts, vptr, W, H, gptr, gidx,
                                    box, gnx, gny, gcell)[0]
        known[kk] = 1 if clear else 2
    return u if known[kk] == 1 else -1


@nb.njit(cache=True)
def timed_search(i: int, m: int, gr: tuple, V: int, gv0: int, hs: tuple, X: np.ndarray,
                 Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
                 ny: int, two_r: float, ends_goal: np.ndarray, q: float, target: int,
                 budget: int, ob: tuple, ways: tuple, arr: np.ndarray, alone: int = 0,
                 tight: bool = False) -> tuple[np.ndarray, np.ndarray, int]:
    """Robot i's earliest way to goal m arriving before ``target`` quanta (module
    docstring): its vertices and their times in quanta (empty when none), and the
    states expanded. Knight moves between lattice nodes (:data:`KNIGHT`) are taken when
    their segment keeps the clearance ``ob[0]`` (exact; ``ob``: the obstacles' grid, and
    ``ob[12]`` the knight moves' answers kept, :func:`_knight`). ``alone``: 1, as if the
    others were only at their last positions from their arrivals ``arr`` on; 2, as if
    there were no other robot (the ways the group repair clears); there waiting never
    arrives earlier, so a vertex is kept at its earliest time only and there are no
    waits; ``tight``: the lower-bound heuristic (:data:`OCTILE_BOUND`), else OCTILE."""
    gr, hs, X, Y, tt, hh, ob, ways = borrowed((gr, hs, X, Y, tt, hh, ob, ways))
    coords, nbr, _, xptr, xidx = gr
    va, vb, ids, sdone, sval = hs[11], hs[12], hs[13], hs[9], hs[10]
    g = gv0 + m
    gx, gy = coords[g, 0], coords[g, 1]
    none = np.zeros(0, np.int64)
    free = 0.0 if alone else free_time(i, gx, gy, X, Y, tt, hh, x0, y0, cs, ny, two_r,
                                       ends_goal, ways)
    if not free < target * q:
        return none, none, 0
    dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
    sv = np.empty(1 << 12, np.int64)
    st, sp, ht, hi, hf = sv.copy(), sv.copy(), sv.copy(), sv.copy(), np.empty(1 << 12)
    # (vertex, time) key -> state: an open-addressing table (keys -1 where empty)
    tk = np.full(1 << 12, -1, np.int64)
    tv = np.empty(1 << 12, np.int64)
    nseen = 0
    div = q * (OCTILE_BOUND if tight else OCTILE)
    sv[0], st[0], sp[0] = V + i, 0, -1
    n = 1
    heap_push(hf, ht, hi, 0, 0.0, 0, 0)
    nh = 1
    span_t = np.int64(target) + 1
    # the robots near the state's vertex, row by row, gathered once for all its moves
    gk = np.empty(64, np.int64)
    gptr = np.zeros(tt.shape[0] + 1, np.int64)
    rep = ways[0]
    work = 0
    found = -1
    while nh > 0 and work < budget:
        s = heap_pop(hf, ht, hi, nh)
        nh -= 1
        v = sv[s]
        t = st[s]
        if v == g and t * q >= free:
            found = s
            break
        work += 1
        ax, ay = coords[v, 0], coords[v, 1]
        r0 = row_at(tt, t * q)
        nrows = 0
        deg = 1 + (8 if v < V else 0) + (xptr[v + 1] - xptr[v])
        for e in range(deg + (8 if v < V else 0)):
            u = move_to(e, v, V, gv0, deg, alone, nbr, xptr, xidx, va, vb, ids, coords, ob)
            if u < 0:
                continue
            bx, by = coords[u, 0], coords[u, 1]
            d = TIMED_WAIT if u == v else int(math.ceil(math.hypot(bx - ax, by - ay) / q - 1e-9))
            t2 = t + d
            if t2 >= target:
                continue
            key = u if alone > 0 else u * span_t + t2  # alone: the earliest time only
            slot = _slot(tk, key)
            if tk[slot] == key and (alone == 0 or st[tv[slot]] <= t2):
                continue
            hu = read_in(m, u, V, va, vb, sdone, sval, dd, dn, wa0, wb0, wna, wnb)
            if hu < 0.0:
                hu = hval(m, u, gr, V, gv0, hs)
                dd, dn, wa0, wb0, wna, wnb = goal_views(m, hs)
            f = t2 + hu / div
            if not f < target - 1e-6:
                continue
            if alone == 1 and not rest_clear(i, ax, ay, bx, by, t * q, t2 * q, X, Y, hh,
                                             x0, y0, cs, ny, two_r, arr):
                continue
            if alone == 0:
                r_end = row_at(tt, t2 * q)
                if r_end - r0 >= nrows:
                    gk, nrows = gather_rows(i, ax, ay, r0, nrows, r_end, hh, x0, y0, cs, ny,
                                            rep, gk, gptr)
                if not motion_near(i, ax, ay, bx, by, t * q, t2 * q, u == g, X, Y, tt,
                                   two_r, ends_goal, ways, gk, gptr, r0):
                    continue
            tk, tv, nseen = _remember(tk, tv, nseen, slot, key, n)
            if n == sv.shape[0]:
                sv, st, sp = doubled(sv, n), doubled(st, n), doubled(sp, n)
            if nh == hf.shape[0]:
                hf, ht, hi = doubled(hf, nh), doubled(ht, nh), doubled(hi, nh)
            sv[n], st[n], sp[n] = u, t2, s
            heap_push(hf, ht, hi, nh, f, t2, n)
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
