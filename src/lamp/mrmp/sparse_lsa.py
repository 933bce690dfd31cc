"""A least-sum assignment over sparse pairs, for the fleet assignment (compiled).

:func:`sparse_assignment` gives every goal its own robot over the allowed pairs only
(CSR by goal), minimising the summed cost: successive shortest augmenting paths with
potentials (the Hungarian method on a sparse graph; Dijkstra with a binary heap over the
reduced costs ``c - u[goal] - v[robot] >= 0``). A dense solver on the (M, N) matrix with
a large stand-in cost for the missing pairs does the same work for every pair of the
matrix; here an augmenting path only visits pairs that exist, which on a fleet's pairs
within the bottleneck (tens per goal) is a small part of them.

Guarantee (``tests/test_mrmp_sparse_lsa.py``, against ``scipy.optimize.
linear_sum_assignment``): when the pairs admit an assignment of every goal, the one
returned has the least sum (to rounding: the potentials are floats); otherwise None.
Deterministic: goals are served in index order, ties go to the first pair found.
"""

from __future__ import annotations

import heapq

import numba as nb
import numpy as np

__all__ = ["sparse_assignment"]


@nb.njit(cache=True)
def _augment(s: int, ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, u: np.ndarray,
             v: np.ndarray, mg: np.ndarray, mr: np.ndarray, dist: np.ndarray,
             prev: np.ndarray, stamp: np.ndarray, fin: np.ndarray, tag: int,
             tree: np.ndarray) -> bool:
    """One shortest augmenting path from free goal ``s`` (reduced costs), the matching
    and the potentials updated; False when no free robot can be reached."""
    heap = [(0.0, -1)]
    heap.pop()
    ntree = 0
    g = s
    dg = 0.0
    end = -1
    dend = 0.0
    while True:
        tree[ntree] = g
        ntree += 1
        for e in range(ptr[g], ptr[g + 1]):
            r = idx[e]
            if stamp[r] == tag and fin[r]:
                continue
            nd = dg + max(val[e] - u[g] - v[r], 0.0)
            if stamp[r] != tag or nd < dist[r]:
                stamp[r] = tag
                fin[r] = False
                dist[r] = nd
                prev[r] = g
                heapq.heappush(heap, (nd, r))
        r = -1
        while len(heap) > 0:
            d, q = heapq.heappop(heap)
            if fin[q] or d > dist[q]:
                continue
            r = q
            break
        if r < 0:
            return False
        fin[r] = True
        if mr[r] < 0:
            end = r
            dend = dist[r]
            break
        g = mr[r]
        dg = dist[r]
    # potentials: every goal of the tree and every finished robot closer than the end
    for k in range(ntree):
        gg = tree[k]
        du = dend - (0.0 if gg == s else dist[mg[gg]])
        u[gg] += du
    for k in range(ntree):
        gg = tree[k]
        if gg != s:
            rr = mg[gg]
            v[rr] -= dend - dist[rr]
    # augment along prev
    r = end
    while True:
        g = prev[r]
        nxt = mg[g]
        mg[g] = r
        mr[r] = g
        if g == s:
            break
        r = nxt
    return True


@nb.njit(cache=True)
def _solve(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, N: int) -> np.ndarray:
    M = ptr.shape[0] - 1
    u = np.zeros(M)
    v = np.zeros(N)
    mg = np.full(M, -1, np.int64)
    mr = np.full(N, -1, np.int64)
    dist = np.zeros(N)
    prev = np.full(N, -1, np.int64)
    stamp = np.zeros(N, np.int64)
    fin = np.zeros(N, np.bool_)
    tree = np.empty(M, np.int64)
    # start: each goal's cheapest pair where that robot is still free (u = that cost)
    for g in range(M):
        best = -1
        for e in range(ptr[g], ptr[g + 1]):
            if best < 0 or val[e] < val[best]:
                best = e
        if best >= 0:
            u[g] = val[best]
            r = idx[best]
            if mr[r] < 0:
                mr[r] = g
                mg[g] = r
    for g in range(M):
        if mg[g] >= 0:
            continue
        if not _augment(g, ptr, idx, val, u, v, mg, mr, dist, prev, stamp, fin, g + 1,
                        tree):
            mg[0] = -2
            return mg
    return mg


def sparse_assignment(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray,
                      N: int) -> np.ndarray | None:
    """``goal -> robot`` of a least-sum assignment of every goal m to its own robot among
    its pairs ``(idx[k], val[k])``, ``ptr[m] <= k < ptr[m + 1]`` (costs >= 0), or None when
    no assignment gives every goal a robot."""
    mg = _solve(np.ascontiguousarray(ptr, dtype=np.int64),
                np.ascontiguousarray(idx, dtype=np.int64),
                np.ascontiguousarray(val, dtype=np.float64), int(N))
    if len(mg) and mg[0] == -2:
        return None
    return mg
