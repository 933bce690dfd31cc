"""The exact pair checks behind :func:`lamp.mrmp.retime.retime`'s lazy locks.

Two moves of one synchronised step that come within ``2r`` of each other are left
unlocked at first; once the earliest times are known, every robot pair with such moves is
checked over the whole retimed plan, in closed form (between consecutive event times of
either robot both move linearly, so the closest approach of each piece is the distance of
the origin to the segment of their relative offsets). A pair that comes closer than the
synchronised plan let it (``min(2r, its closest approach there)``) has all its moves
locked, and the times are found again.

Also here: the segment distance and the union-find that :mod:`lamp.mrmp.retime` uses.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["find", "lock_violations", "segment_distance", "union"]


@nb.njit(cache=True, inline="always")
def segment_distance(ax: float, ay: float, bx: float, by: float, cx: float, cy: float, dx: float,
             dy: float) -> float:
    """Distance between segments ab and cd (points when a == b or c == d)."""
    ux = bx - ax
    uy = by - ay
    vx = dx - cx
    vy = dy - cy
    wx = ax - cx
    wy = ay - cy
    a = ux * ux + uy * uy
    b = ux * vx + uy * vy
    c = vx * vx + vy * vy
    d = ux * wx + uy * wy
    e = vx * wx + vy * wy
    den = a * c - b * b
    # closest parameters (s on ab, t on cd), clamped (Eberly / Ericson)
    if a <= 1e-18 and c <= 1e-18:
        return math.hypot(wx, wy)
    if a <= 1e-18:
        s = 0.0
        t = min(1.0, max(0.0, e / c))
    elif c <= 1e-18:
        t = 0.0
        s = min(1.0, max(0.0, -d / a))
    else:
        s = min(1.0, max(0.0, (b * e - c * d) / den)) if den > 1e-18 else 0.0
        t = (b * s + e) / c
        if t < 0.0:
            t = 0.0
            s = min(1.0, max(0.0, -d / a))
        elif t > 1.0:
            t = 1.0
            s = min(1.0, max(0.0, (b - d) / a))
    px = wx + s * ux - t * vx
    py = wy + s * uy - t * vy
    return math.hypot(px, py)


@nb.njit(cache=True)
def find(parent: np.ndarray, x: int) -> int:
    r = x
    while parent[r] != r:
        r = parent[r]
    while parent[x] != r:
        nx = parent[x]
        parent[x] = r
        x = nx
    return r


@nb.njit(cache=True)
def union(parent: np.ndarray, x: int, y: int) -> None:
    """Merge the sets of x and y (the smaller root id becomes the root)."""
    rx = find(parent, x)
    ry = find(parent, y)
    if rx != ry:
        parent[max(rx, ry)] = min(rx, ry)


@nb.njit(cache=True)
def _pair_min(i: int, j: int, first: np.ndarray, rob_end: np.ndarray, seg: np.ndarray,
              ev0: np.ndarray, ev1: np.ndarray, T: np.ndarray) -> float:
    """Closest approach of robots i and j over the whole retimed plan (both move linearly
    between consecutive event times of either)."""
    a = first[i]
    a_end = rob_end[i]
    b = first[j]
    b_end = rob_end[j]
    t = 0.0
    best = np.inf
    while True:
        ta1 = T[ev1[a]] if ev1[a] >= 0 else np.inf
        tb1 = T[ev1[b]] if ev1[b] >= 0 else np.inf
        t1 = min(ta1, tb1)
        if t1 == np.inf:
            # both in their final stays
            d = math.hypot(seg[a, 0] - seg[b, 0], seg[a, 1] - seg[b, 1])
            return min(best, d)
        # positions at t and t1
        xa0, ya0 = _at(a, t, seg, ev0, ev1, T)
        xa1, ya1 = _at(a, t1, seg, ev0, ev1, T)
        xb0, yb0 = _at(b, t, seg, ev0, ev1, T)
        xb1, yb1 = _at(b, t1, seg, ev0, ev1, T)
        d = segment_distance(0.0, 0.0, 0.0, 0.0, xa0 - xb0, ya0 - yb0, xa1 - xb1, ya1 - yb1)
        if d < best:
            best = d
        t = t1
        if ta1 <= t1 and a < a_end - 1:
            a += 1
        if tb1 <= t1 and b < b_end - 1:
            b += 1


@nb.njit(cache=True, inline="always")
def _at(a: int, t: float, seg: np.ndarray, ev0: np.ndarray, ev1: np.ndarray,
        T: np.ndarray) -> tuple[float, float]:
    t0 = T[ev0[a]]
    t1 = T[ev1[a]] if ev1[a] >= 0 else t0
    if t1 <= t0:
        return seg[a, 2], seg[a, 3]
    f = min(1.0, max(0.0, (t - t0) / (t1 - t0)))
    return seg[a, 0] + f * (seg[a, 2] - seg[a, 0]), seg[a, 1] + f * (seg[a, 3] - seg[a, 1])


@nb.njit(cache=True)
def _sync_min(i: int, j: int, P: np.ndarray) -> float:
    """Closest approach of robots i and j in the synchronised plan."""
    best = np.inf
    for t in range(P.shape[0] - 1):
        d = segment_distance(0.0, 0.0, 0.0, 0.0, P[t, i, 0] - P[t, j, 0], P[t, i, 1] - P[t, j, 1],
                     P[t + 1, i, 0] - P[t + 1, j, 0], P[t + 1, i, 1] - P[t + 1, j, 1])
        if d < best:
            best = d
    return best


@nb.njit(cache=True)
def lock_violations(P: np.ndarray, rob: np.ndarray, seg: np.ndarray, ev0: np.ndarray,
                     ev1: np.ndarray, T: np.ndarray, pa: np.ndarray, pb: np.ndarray,
                     pend: np.ndarray, parent: np.ndarray, two_r: float) -> int:
    """Check every robot pair with unlocked close moves (``pend``) over the retimed plan;
    where a pair comes closer than ``min(2r, its closest approach in the synchronised
    plan)``, lock all its unlocked moves. Returns the number of pairs locked."""
    N = P.shape[1]
    S = rob.shape[0]
    first = np.zeros(N, np.int64)
    rob_end = np.zeros(N, np.int64)
    for a in range(S - 1, -1, -1):
        first[rob[a]] = a
    for a in range(S):
        rob_end[rob[a]] = a + 1
    # robot pairs, each once (pending entries sorted by pair)
    key = np.empty(pa.shape[0], np.int64)
    for k in range(pa.shape[0]):
        i = rob[pa[k]]
        j = rob[pb[k]]
        key[k] = min(i, j) * N + max(i, j)
    o = np.argsort(key, kind="mergesort")
    locked = 0
    k = 0
    while k < o.shape[0]:
        kk = key[o[k]]
        k1 = k
        anyp = False
        while k1 < o.shape[0] and key[o[k1]] == kk:
            anyp = anyp or pend[o[k1]]
            k1 += 1
        if anyp:
            i = kk // N
            j = kk % N
            need = min(two_r, _sync_min(i, j, P)) - 1e-9
            if _pair_min(i, j, first, rob_end, seg, ev0, ev1, T) < need:
                for q in range(k, k1):
                    e = o[q]
                    if pend[e]:
                        pend[e] = False
                        union(parent, ev0[pa[e]], ev0[pb[e]])
                        union(parent, ev1[pa[e]], ev1[pb[e]])
                locked += 1
        k = k1
    return locked
