"""Gspi's heuristic: one lazy, windowed Dijkstra per goal over the lattice (compiled).

Goal m's search starts from the lattice nodes linked to the goal point (seeded with the
link lengths plus :data:`EPS`) and is *resumed lazily*, only as far as the queries need
(pypibt's lazy distance table). Its queue is Dial's: buckets of width ``L`` (the lattice
step); every edge is at least ``L`` long, so all nodes in the lowest non-empty bucket are
final, and a settle costs O(1) instead of a heap operation.

Each search lives in a square *window* of lattice indices centred on its goal, of radius
``R``: the window holds every node within Euclidean distance ``R + 1.5 L`` of the goal
point, and only buckets below ``R`` are processed. When a query needs more, the window
grows (at least doubling for a query, by a quarter at least, or to the room asked for,
when the search is expanded to a bound, :func:`expand_to`), keeping what was settled and
queued, and the settled nodes on its old border relax their edges into the new part.

Guarantee (tested against a full Dijkstra on the whole lattice): every value returned by
:func:`lattice_h`/:func:`hval` is the exact shortest lattice distance to the goal (inf when
there is none), and :func:`lamp.mrmp.heuristic_reads.hval_below` is exact below its
bound. Why the window does not change it: a node at distance ``d < R + 1.5 L`` has a
shortest path of length ``d`` from the goal point, every point of which is within ``d``
of it, hence inside the window; the buckets processed (below ``R``) hold only nodes at
distance ``< R + L``; a node outside the window is farther than ``R + 1.5 L`` and so
never belongs in a processed bucket. A relaxation does not ask whether its neighbour is
settled: one settled in bucket ``k`` or before is below ``(k + 1) L``, no more than the
relaxed value, so it is never improved (the values are a heap Dijkstra's, bit for bit).

Memory and time grow with the area the queries reach, not with the map: 400 robots with
goals about 1.5 m from their starts on a 9.6 m map settle about 3,300 nodes per goal on
the 3 cm lattice, where whole-map tables would hold 58,000 per goal.

Vertices: ``0..V-1`` lattice nodes, ``V..V+N-1`` starts, ``V+N..`` goals (see
:mod:`lamp.mrmp.gspi_kernels`); the special vertices' values are memoised in
``sdone``/``sval`` (a start's value is the best of its links, a goal's own value 0).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba as nb
import numpy as np
from numba.extending import typeof_impl
from numba.typed import List

__all__ = ["EPS", "GoalDistances", "expand_to", "hval", "hval_pairs", "lattice_h",
           "start_costs"]

#: Added to every heuristic value but the goal vertex's own, so that a lattice node (or a
#: start) that coincides with a goal never ties with the goal vertex.
EPS = 1e-6
#: Radius of a goal's first window, in lattice steps.
_FIRST_RADIUS_STEPS = 12
#: Initial capacity of each bucket of a goal's queue (doubled when full).
_BUCKET_CAP = 64


class GoalDistances(NamedTuple):
    """Lazy windowed distance tables, one per goal m (see the module docstring).

    ``win[m] = (a0, b0, na, nb, k)``: window origin and size in lattice indices and the
    bucket being processed; ``rad[m]`` the window's radius ``R`` (inf once the window is
    the whole lattice, 0 before the first query); ``dist``/``done``/``em`` per goal
    (distance, settled, edge bits), indexed by the window-local index
    ``(b - b0 + 1) * (na + 2) + (a - a0 + 1)`` (the window and a ring of one entry around
    it, settled and without edges); ``bucket[m]`` (slots, cap: window-local indices) and
    ``bcnt[m]`` the circular bucket queue. ``sptr``/``snode``/``scost``: goal m's seed
    nodes and costs (CSR). ``va``/``vb``: lattice index of each node; ``ids``: node id per
    lattice index (-1 none); ``da``/``db``: the lattice directions; ``centre[m]``: goal m
    in lattice index units; ``step``: lattice step (m); ``emask``: the lattice's edge bits
    per lattice index (``Lattice.edge_mask``).
    """

    win: np.ndarray  # (M, 5) int64
    rad: np.ndarray  # (M,)
    dist: Any  # typed List of float64 arrays
    done: Any  # typed List of uint8 arrays
    bucket: Any  # typed List of (slots, cap) int32 arrays
    bcnt: np.ndarray  # (M, slots) int64
    sptr: np.ndarray  # (M+1,) int64
    snode: np.ndarray  # int64
    scost: np.ndarray  # float64
    sdone: np.ndarray  # (M, N+M) bool
    sval: np.ndarray  # (M, N+M)
    va: np.ndarray  # (V,) int64
    vb: np.ndarray  # (V,) int64
    ids: np.ndarray  # (nb, na) int64
    da: np.ndarray  # (8,) int64
    db: np.ndarray  # (8,) int64
    centre: np.ndarray  # (M, 2)
    step: float
    em: Any  # typed List of uint8 arrays
    emask: np.ndarray  # (nb, na) uint8

    @staticmethod
    def build(goal_links: list[tuple[np.ndarray, np.ndarray]], goals: np.ndarray,
              lat: Any, n_special: int) -> GoalDistances:
        """Empty tables for the goals at ``goals`` (M, 2), seeded with their lattice
        links ``(nodes, lengths)`` (+ EPS), on the lattice ``lat`` (a ``Lattice``)."""
        from lamp.mrmp.distance_field import DIRS

        M = len(goal_links)
        sptr = np.cumsum([0] + [len(n) for n, _ in goal_links]).astype(np.int64)
        snode = np.concatenate([np.zeros(0, np.int64)]
                               + [n.astype(np.int64) for n, _ in goal_links])
        scost = np.concatenate([np.zeros(0)] + [c.astype(float) + EPS for _, c in goal_links])
        # slots: the longest edge is a diagonal (< 2 L), the seeds reach max(scost)
        span = int(np.ceil(scost.max() / lat.step)) if len(scost) else 0
        slots = 4
        while slots < span + 4:
            slots *= 2
        centre = np.asarray(goals, dtype=np.float64).reshape(-1, 2) / lat.step - lat.offset
        dist, done, bucket, em = _new_lists(max(M, 1), slots)
        return GoalDistances(
            np.zeros((M, 5), dtype=np.int64), np.zeros(M), dist, done, bucket,
            np.zeros((M, slots), dtype=np.int64), sptr, snode, scost,
            np.zeros((M, n_special), dtype=np.bool_), np.zeros((M, n_special)), lat.va, lat.vb,
            lat.ids, DIRS[:, 0].copy(), DIRS[:, 1].copy(), np.ascontiguousarray(centre),
            float(lat.step), em, lat.edge_mask)

# The typed lists are made and read in compiled code only: Numba compiles its list
# helpers anew in every process (about 1 s) when Python code builds or reads them.


#: Numba's types of the GoalDistances seen, by the kinds of their fields (:func:`_kind`).
_TYPES: dict[tuple, Any] = {}


def _kind(x: Any, c: Any) -> Any:
    """What Numba's type of a field depends on: an array's class, dtype, dimensions,
    layout flags and writability (``numba.core.typing.typeof._typeof_ndarray``); for any
    other field, its Numba type."""
    if type(x) is np.ndarray:
        f = x.flags
        return (x.dtype, x.ndim, f.c_contiguous, f.f_contiguous, f.writeable, f.aligned)
    return typeof_impl(x, c)


@typeof_impl.register(GoalDistances)
def _typeof_goal_distances(val: GoalDistances, c: Any) -> Any:
    """Numba's type of ``val`` as its tuple rule gives it, kept by the kinds of the
    fields: a tuple of typed lists has no fingerprint in Numba's dispatcher, so each
    compiled call typed its 20 fields in Python (0.14 ms; with the kinds 0.04 ms)."""
    key = (getattr(c, "purpose", None),) + tuple(_kind(x, c) for x in val)
    ty = _TYPES.get(key)
    if ty is None:
        ty = _TYPES[key] = typeof_impl.dispatch(tuple)(val, c)
    return ty


@nb.njit(cache=True)
def _new_lists(M: int, slots: int) -> tuple[Any, Any, Any, Any]:
    dist = List()
    done = List()
    bucket = List()
    em = List()
    for _ in range(M):
        dist.append(np.zeros(0))
        done.append(np.zeros(0, np.uint8))
        bucket.append(np.zeros((slots, 0), np.int32))
        em.append(np.zeros(0, np.uint8))
    return dist, done, bucket, em


# ---- one goal's bucket queue and window ----------------------------------------------
# A window of na x nb lattice indices is stored with a ring of one entry around it
# (row stride na + 2): ring entries count as settled, have no edges and hold -inf, so
# the search needs no bounds checks; window entries hold their node's edge bits (``em``).


@nb.njit(cache=True)
def _local(m: int, v: int, hs: tuple) -> int:
    """Index of lattice node v in goal m's window arrays (-1 outside the window)."""
    win, va, vb = hs[0], hs[11], hs[12]
    a = va[v] - win[m, 0]
    b = vb[v] - win[m, 1]
    na = win[m, 2]
    if 0 <= a < na and 0 <= b < win[m, 3]:
        return (b + 1) * (na + 2) + a + 1
    return -1


@nb.njit(cache=True)
def _push(m: int, j: int, d: float, hs: tuple) -> None:
    """Queue window entry j at distance d (in bucket floor(d / L), never below the bucket
    being processed)."""
    win, bucket_l, bcnt, step = hs[0], hs[4], hs[5], hs[17]
    slots = bcnt.shape[1]
    k = max(int(d / step), win[m, 4])
    s = k & (slots - 1)
    c = bcnt[m, s]
    if c == bucket_l[m].shape[1]:
        _grow_buckets(m, bucket_l)
    bucket_l[m][s, c] = j
    bcnt[m, s] = c + 1


@nb.njit(cache=True)
def _grow_buckets(m: int, bucket_l: Any) -> None:
    """Double the capacity of goal m's buckets (at least :data:`_BUCKET_CAP`)."""
    bk = bucket_l[m]
    grown = np.empty((bk.shape[0], max(_BUCKET_CAP, 2 * bk.shape[1])), dtype=np.int32)
    grown[:, : bk.shape[1]] = bk
    bucket_l[m] = grown


@nb.njit(cache=True)
def _window_arrays(a0: int, b0: int, na: int, nb_: int,
                   emask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fresh (dist, done, edge bits) of a window with its ring (row slices: compiled to
    vector stores, half the time of an entry-by-entry loop)."""
    P = na + 2
    n = P * (nb_ + 2)
    d = np.full(n, -np.inf)  # the ring: below every distance, so never improved
    dn = np.ones(n, dtype=np.uint8)
    em = np.zeros(n, dtype=np.uint8)
    for b in range(nb_):
        r = (b + 1) * P + 1
        d[r:r + na] = np.inf
        dn[r:r + na] = 0
        em[r:r + na] = emask[b + b0, a0:a0 + na]
    return d, dn, em


@nb.njit(cache=True)
def _open_window(m: int, radius: float, nbr: np.ndarray, dlen: np.ndarray,
                 hs: tuple) -> None:
    """Give goal m the window of radius ``radius`` (metres), keeping what its search has
    settled and queued; the first window is seeded with the goal's links."""
    (win, rad, dist_l, done_l, bucket_l, bcnt, sptr, snode, scost, _, _, va, vb, ids, da, db,
     centre, step, em_l, emask) = hs
    nbt, nat = ids.shape
    k = int(math.ceil(radius / step)) + 2
    ca = int(math.floor(centre[m, 0] + 0.5))
    cb = int(math.floor(centre[m, 1] + 0.5))
    a0 = max(0, ca - k)
    b0 = max(0, cb - k)
    a1 = min(nat - 1, ca + k)
    b1 = min(nbt - 1, cb + k)
    full = a0 == 0 and b0 == 0 and a1 == nat - 1 and b1 == nbt - 1
    if a1 < a0 or b1 < b0:  # the goal lies far outside the lattice: an empty window
        a0, b0, a1, b1 = 0, 0, -1, -1
    na = a1 - a0 + 1
    nb_ = b1 - b0 + 1
    P = na + 2
    d, dn, em = _window_arrays(a0, b0, na, nb_, emask)
    first = rad[m] == 0.0
    oa0, ob0, ona, onb = win[m, 0], win[m, 1], win[m, 2], win[m, 3]
    oP = ona + 2
    old_d = dist_l[m]
    old_dn = done_l[m]
    old_bk = bucket_l[m]
    slots = bcnt.shape[1]
    old_cnt = bcnt[m].copy()
    for s in range(slots):
        bcnt[m, s] = 0
    bucket_l[m] = np.empty((slots, max(_BUCKET_CAP, old_bk.shape[1])), dtype=np.int32)
    dist_l[m] = d
    done_l[m] = dn
    em_l[m] = em
    win[m, 0] = a0
    win[m, 1] = b0
    win[m, 2] = na
    win[m, 3] = nb_
    rad[m] = np.inf if full else radius
    if first:
        for s in range(sptr[m], sptr[m + 1]):
            v = snode[s]
            a = va[v] - a0
            b = vb[v] - b0
            if 0 <= a < na and 0 <= b < nb_:
                j = (b + 1) * P + a + 1
                if scost[s] < d[j]:
                    d[j] = scost[s]
                    _push(m, j, scost[s], hs)
        return
    # carry the old window over (it lies inside the new one)
    for ob in range(onb):  # row by row (slices: vector copies)
        oj = (ob + 1) * oP + 1
        j = (ob + ob0 - b0 + 1) * P + (oa0 - a0 + 1)
        d[j:j + ona] = old_d[oj:oj + ona]
        dn[j:j + ona] = old_dn[oj:oj + ona]
    for s in range(slots):
        for c in range(old_cnt[s]):
            oj = old_bk[s, c]
            j = (oj // oP + ob0 - b0) * P + (oj % oP + oa0 - a0)
            if dn[j] == 0:
                _push(m, j, d[j], hs)
    # settled nodes on the old border: relax their edges that leave the old window
    for ob in range(onb):
        for oa in range(ona):
            if not (oa == 0 or ob == 0 or oa == ona - 1 or ob == onb - 1):
                continue
            oj = (ob + 1) * oP + oa + 1
            if old_dn[oj] == 0:
                continue
            du = old_d[oj]
            msk = emask[ob + ob0, oa + oa0]
            for e in range(8):
                if not (msk >> e) & 1:
                    continue
                wa = oa + da[e]
                wb = ob + db[e]
                if 0 <= wa < ona and 0 <= wb < onb:
                    continue
                j = (wb + ob0 - b0 + 1) * P + (wa + oa0 - a0 + 1)
                nd = du + dlen[e]
                if nd < d[j]:
                    d[j] = nd
                    _push(m, j, nd, hs)


@nb.njit(cache=True)
def _settle(target: int, lim: float, k: int, dlen: np.ndarray, dist: np.ndarray,
            done: np.ndarray, em: np.ndarray, bk: np.ndarray, cnt: np.ndarray, P: int,
            da: np.ndarray, db: np.ndarray, step: float) -> tuple[int, int]:
    """The search loop of one goal (Dial's buckets of width L: an edge is at least L
    long, so every node in the lowest non-empty bucket is final). Returns (bucket,
    status): 0 window entry ``target`` settled or ``lim`` reached, 1 queue empty, 2 a
    bucket may be full. (Kept apart from the growth of the buckets: an array variable
    reassigned inside a Numba loop costs a reference count on every access. Indices are
    unsigned, so that Numba adds no wraparound of negative ones to every access: a
    negative offset wraps, and ``j + off`` wraps back to the entry; 5 % less time.)"""
    slots = cnt.shape[0]
    mask = slots - 1
    cap = bk.shape[1] - 8
    inv = 1.0 / step
    off = (da + db * P).astype(np.uint64)
    buf = np.empty(8, dtype=np.uint64)
    bnd = np.empty(8)
    left = 0
    high = 0
    for q in range(slots):
        left += cnt[q]
        high = max(high, cnt[q])
    while target < 0 or done[target] == 0:
        s = np.uint64(k & mask)
        if cnt[s] == 0:
            if left == 0:
                return k, 1
            k += 1
            continue
        if k * step >= lim:
            return k, 0
        if high > cap:
            return k, 2
        c = cnt[s] - 1
        cnt[s] = c
        left -= 1
        j = np.uint64(bk[s, np.uint64(c)])
        if done[j]:
            continue
        done[j] = 1
        du = dist[j]
        msk = em[j]
        # eight relaxations decided without branches (a settled neighbour or the ring is
        # never improved: module docstring), the improved ones queued in direction order
        nb_ = np.uint64(0)
        for e in range(8):
            jw = j + off[e]
            nd = du + dlen[e]
            buf[nb_] = jw
            bnd[nb_] = nd
            nb_ += np.uint64(((msk >> e) & 1) & (nd < dist[jw]))
        for t in range(nb_):
            jw = buf[t]
            nd = bnd[t]
            dist[jw] = nd
            q = np.uint64(max(int(nd * inv), k) & mask)
            cq = cnt[q] + 1
            bk[q, np.uint64(cq - 1)] = np.int32(jw)
            cnt[q] = cq
            left += 1
            if cq > high:
                high = cq
    return k, 0


@nb.njit(cache=True)
def _run_until(m: int, target: int, bound: float, nbr: np.ndarray, dlen: np.ndarray,
               hs: tuple) -> bool:
    """Resume goal m's search until window entry ``target`` is settled (-1: none), or
    every bucket below ``min(bound, R)`` is processed; False when the queue ran empty."""
    (win, rad, dist_l, done_l, bucket_l, bcnt, _, _, _, _, _, _, _, _, da, db, _,
     step, em_l, _) = hs
    lim = min(bound, rad[m])
    while True:
        k, status = _settle(target, lim, win[m, 4], dlen, dist_l[m], done_l[m], em_l[m],
                            bucket_l[m], bcnt[m], win[m, 2] + 2, da, db, step)
        win[m, 4] = k
        if status != 2:
            return status == 0
        _grow_buckets(m, bucket_l)


@nb.njit(cache=True)
def lattice_h(m: int, v: int, nbr: np.ndarray, dlen: np.ndarray, hs: tuple) -> float:
    """Exact lattice distance from node v to goal m (inf when there is no path)."""
    rad, dist_l, done_l = hs[1], hs[2], hs[3]
    va, vb, centre, step = hs[11], hs[12], hs[16], hs[17]
    if rad[m] == 0.0:
        _open_window(m, _FIRST_RADIUS_STEPS * step, nbr, dlen, hs)
    while True:
        j = _local(m, v, hs)
        if j >= 0:
            if done_l[m][j]:
                return dist_l[m][j]
            _run_until(m, j, np.inf, nbr, dlen, hs)
            if done_l[m][j]:
                return dist_l[m][j]
        if rad[m] == np.inf:
            return np.inf  # the whole lattice is searched and v was never reached
        need = step * (math.hypot(va[v] - centre[m, 0], vb[v] - centre[m, 1]) + 2.0)
        _open_window(m, max(2.0 * rad[m], need), nbr, dlen, hs)


@nb.njit(cache=True)
def expand_to(m: int, bound: float, nbr: np.ndarray, dlen: np.ndarray, hs: tuple,
              room: float = 0.0) -> None:
    """Settle every node of goal m's search closer than ``bound`` (metres); a window
    opened or grown for it reaches ``room`` at least (later bounds up to there resume
    the search in place: growing a window copies all of it)."""
    rad, step = hs[1], hs[17]
    if rad[m] == 0.0:
        _open_window(m, max(bound, room, _FIRST_RADIUS_STEPS * step), nbr, dlen, hs)
    elif rad[m] < bound:
        _open_window(m, max(bound, room, 1.25 * rad[m]), nbr, dlen, hs)
    _run_until(m, -1, bound, nbr, dlen, hs)


@nb.njit(cache=True)
def _special(m: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    """Best link of special vertex v to goal m: each link's length plus its lattice node's
    distance, or the direct link."""
    coords, nbr, dlen, xptr, xidx = gr
    if v == gv0 + m:
        return 0.0
    best = np.inf
    for e in range(xptr[v], xptr[v + 1]):
        n = xidx[e]
        dx = coords[v, 0] - coords[n, 0]
        dy = coords[v, 1] - coords[n, 1]
        ln = math.sqrt(dx * dx + dy * dy)
        if n < V:
            c = ln + lattice_h(m, n, nbr, dlen, hs)
        elif n == gv0 + m:
            c = ln + EPS
        else:
            continue
        if c < best:
            best = c
    return best


@nb.njit(cache=True)
def hval(m: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    """Exact heuristic distance of vertex v (lattice or special) to goal m."""
    if v < V:
        return lattice_h(m, v, gr[1], gr[2], hs)
    sdone = hs[9]
    sval = hs[10]
    k = v - V
    if sdone[m, k]:
        return sval[m, k]
    best = _special(m, v, gr, V, gv0, hs)
    sdone[m, k] = True
    sval[m, k] = best
    return best


@nb.njit(cache=True)
def hval_pairs(pm: np.ndarray, pv: np.ndarray, gr: tuple, V: int, gv0: int,
               hs: tuple) -> np.ndarray:
    """Exact distances of the pairs (goal ``pm[k]``, vertex ``pv[k]``), best grouped by
    goal: a goal's first window reaches 1.25 times the farthest straight line of its
    group (no regrowth where the lattice distances are near the straight lines)."""
    coords = gr[0]
    out = np.empty(pm.shape[0])
    k = 0
    while k < pm.shape[0]:
        m = pm[k]
        e = k
        far = 0.0
        while e < pm.shape[0] and pm[e] == m:
            far = max(far, math.hypot(coords[pv[e], 0] - coords[gv0 + m, 0],
                                      coords[pv[e], 1] - coords[gv0 + m, 1]))
            e += 1
        if hs[1][m] == 0.0:
            _open_window(m, max(1.25 * far, _FIRST_RADIUS_STEPS * hs[17]), gr[1], gr[2], hs)
        for q in range(k, e):
            out[q] = hval(m, pv[q], gr, V, gv0, hs)
        k = e
    return out


def start_costs(m0: int, m1: int, N: int, gr: tuple, V: int, hs: tuple) -> np.ndarray:
    """(N, m1 - m0) exact distances of the start vertices to goals m0..m1-1."""
    pm = np.repeat(np.arange(m0, m1, dtype=np.int64), N)
    pv = np.tile(np.arange(V, V + N, dtype=np.int64), m1 - m0)
    return hval_pairs(pm, pv, gr, V, V + N, hs).reshape(m1 - m0, N).T.copy()
