"""Rows of a Gspi plan: synchronised (:func:`densify`), or retimed (:func:`retime`).

:func:`densify` cuts each synchronised step into equal sub-steps (every robot's move of a
step ends on the same row); :func:`retime`, for fleets, gives every robot its own speed
along the same path.

Gspi's steps are synchronised: a step lasts as long as its longest move, so a robot
moving along a lattice axis (3 cm) while another moves diagonally (4.2 cm) goes at 71 %
of its speed, and a robot that waits waits the whole step. :func:`retime` keeps every
robot's path (the same segments, so the same obstacle clearance) and gives each move its
own duration, subject to ordering constraints that keep every robot pair as far apart as
the synchronised plan did.

**States.** Robot i's plan is a sequence of *states*: each move of step s (segment
``P[s-1, i] -> P[s, i]``), or a *stay*: a run of steps in which it does not move (the last
one lasts for ever). Each state spans an interval of step indices and has a start and an
end *event*, whose new times are unknowns (``T = 0`` at index 0).

**Constraints.** Two states of different robots are *close* when their segments (points
for stays) come within ``2r`` of each other; other pairs are safe whatever their timing.
For a close pair:

- their step ranges do not overlap (one ends at step index ``e``, the other starts later):
  the first ends before the second starts (``T_end(first) <= T_start(second)``);
- both are moves of the same step: *locked*, the same start event and the same end event
  (both move uniformly over the same interval, so their relative motion is exactly the
  synchronised step that Gspi checked). Lazily: when both ends of the two moves are at
  least ``2r`` apart, the pair is left unlocked; once the times are found, every robot
  pair with such moves is checked exactly over the whole retimed plan
  (:func:`lamp.mrmp.retime_pairs.lock_violations`), and a pair that comes closer than in
  the synchronised plan has its moves locked and the times are found again (at most
  ``max_rounds`` times, then every such pair is locked);
- a move of step s and a stay spanning s: the move lies within the stay
  (``T_start(stay) <= T_start(move)``, ``T_end(move) <= T_end(stay)``): the stationary
  robot is where it was during step s, so the relative motion is again the checked one;
- two stays with overlapping ranges: both stationary at positions that coexisted in the
  synchronised plan; no constraint.

And each move lasts at least its length (unit speed), in whole *quanta* ``q``.

**Why it is safe.** For a robot pair without unlocked moves: at any instant robot i is in
one state and robot j in another; if the two are not close they are at least ``2r``
apart; if they are close they overlap in time only as the cases above allow, where the
relative positions are those of the synchronised plan; at an instant where one state ends
as the other begins, the next states of both are examined the same way. A pair with
unlocked moves has been checked exactly.

**Times.** The synchronised plan's own times (each step rounded up to whole quanta)
satisfy every constraint, so the earliest times exist and are found by a longest path over
the events in step-index order (all edges go from an index to the same or a larger one;
within one index the zero-length edges are relaxed to a fixed point).

**Output.** Rows at every event time, subdivided so that no robot moves more than
``max_spacing`` between rows; between two rows every robot moves linearly within one of
its states (the rows are exact). The makespan at unit speed is at most that of the
synchronised plan with each step rounded up to whole quanta: those times are feasible,
and the earliest ones are no later.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.neighbours import cell_hash, cell_start, cell_starts, doubled
from lamp.mrmp.retime_pairs import find, lock_violations, segment_distance, union

__all__ = ["RETIME_QUANTA", "densify", "drop_waits", "retime"]

#: Event times are multiples of the lattice step over this: a diagonal move (sqrt(2) L)
#: then takes 10 quanta, 1 % more than its length, an axis move exactly 7.
RETIME_QUANTA = 7.0


@nb.njit(cache=True)
def _states(P: np.ndarray) -> tuple:
    """Each robot's states (see module doc), in robot order then step order: robot, first
    and last step index (``hi = K + 1`` for the final stay), segment ends, move flag,
    start and end event ids (``-1`` for the final stay's end); event index per event."""
    K1, N, _ = P.shape
    K = K1 - 1
    cap = N * (K + 1) + N
    rob = np.empty(cap, np.int64)
    lo = np.empty(cap, np.int64)
    hi = np.empty(cap, np.int64)
    seg = np.empty((cap, 4))
    move = np.empty(cap, np.bool_)
    ev0 = np.empty(cap, np.int64)
    ev1 = np.empty(cap, np.int64)
    evk = np.empty(cap + N, np.int64)
    ns = 0
    ne = 0
    for i in range(N):
        evk[ne] = 0
        cur_ev = ne
        ne += 1
        s = 1
        while s <= K + 1:
            moving = s <= K and (P[s, i, 0] != P[s - 1, i, 0] or P[s, i, 1] != P[s - 1, i, 1])
            rob[ns] = i
            lo[ns] = s
            ev0[ns] = cur_ev
            if moving:
                hi[ns] = s
                seg[ns, 0] = P[s - 1, i, 0]
                seg[ns, 1] = P[s - 1, i, 1]
                seg[ns, 2] = P[s, i, 0]
                seg[ns, 3] = P[s, i, 1]
                move[ns] = True
                s += 1
            else:
                e = s
                while e <= K and P[e, i, 0] == P[e - 1, i, 0] and P[e, i, 1] == P[e - 1, i, 1]:
                    e += 1
                # steps s .. e-1 are waits; the stay ends at index e - 1 (or never)
                last = e - 1 if e <= K else K + 1
                hi[ns] = last
                seg[ns, 0] = P[s - 1, i, 0]
                seg[ns, 1] = P[s - 1, i, 1]
                seg[ns, 2] = P[s - 1, i, 0]
                seg[ns, 3] = P[s - 1, i, 1]
                move[ns] = False
                s = last + 1
            if hi[ns] <= K:
                evk[ne] = hi[ns]
                ev1[ns] = ne
                cur_ev = ne
                ne += 1
            else:
                ev1[ns] = -1
            ns += 1
    return rob[:ns], lo[:ns], hi[:ns], seg[:ns], move[:ns], ev0[:ns], ev1[:ns], evk[:ne]


@nb.njit(cache=True)
def _close_pairs(rob: np.ndarray, lo: np.ndarray, hi: np.ndarray, seg: np.ndarray,
                 move: np.ndarray, two_r: float) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (a < b) of states of different robots whose segments come within
    ``two_r``, but for two stays at once (positions that coexisted); a spatial hash of
    the segments' midpoints (cells wider than ``2r`` plus the longest segment), each pair
    met once: the states in key order, each against the later entries of its own cell
    column (three consecutive keys) and every entry of the next column."""
    S = rob.shape[0]
    mx = np.empty(S)
    my = np.empty(S)
    half = 0.0
    for a in range(S):
        mx[a] = 0.5 * (seg[a, 0] + seg[a, 2])
        my[a] = 0.5 * (seg[a, 1] + seg[a, 3])
        half = max(half, 0.5 * math.hypot(seg[a, 2] - seg[a, 0], seg[a, 3] - seg[a, 1]))
    cs = two_r + 2.0 * half + 1e-9
    key, order, skey, ny = cell_hash(mx, my, cs)
    table, first = cell_starts(skey, ny)
    sx = mx[order]
    sy = my[order]
    A = np.empty(4 * S + 16, np.int64)
    B = np.empty(4 * S + 16, np.int64)
    n = 0
    for p in range(S):
        a = order[p]
        for col in range(2):
            kk = skey[p] + col * ny - 1
            q0 = p + 1 if col == 0 else cell_start(kk, skey, table, first)
            q1 = cell_start(kk + 3, skey, table, first)
            for q in range(q0, q1):
                ddx = sx[q] - sx[p]
                ddy = sy[q] - sy[p]
                if ddx * ddx + ddy * ddy > cs * cs:
                    continue
                b = order[q]
                if rob[b] == rob[a]:
                    continue
                if not move[a] and not move[b] and hi[a] >= lo[b] and hi[b] >= lo[a]:
                    continue
                if segment_distance(seg[a, 0], seg[a, 1], seg[a, 2], seg[a, 3],
                                    seg[b, 0], seg[b, 1], seg[b, 2], seg[b, 3]) >= two_r:
                    continue
                if n == A.shape[0]:
                    A = doubled(A, n)
                    B = doubled(B, n)
                A[n] = min(a, b)
                B[n] = max(a, b)
                n += 1
    return A[:n], B[:n]


@nb.njit(cache=True)
def _constraints(rob: np.ndarray, lo: np.ndarray, hi: np.ndarray, seg: np.ndarray,
                 move: np.ndarray, ev0: np.ndarray, ev1: np.ndarray, parent: np.ndarray,
                 two_r: float, lazy: bool) -> tuple:
    """The close pairs' constraints (module docstring): locks merged in ``parent``
    (union-find over events), orderings returned as edges (from, to) meaning
    ``T[to] >= T[from]``, and, when ``lazy``, the pairs of moves of one step left
    unlocked for now (both ends at least ``2r`` apart in the synchronised plan)."""
    A, B = _close_pairs(rob, lo, hi, seg, move, two_r)
    n = A.shape[0]
    ef = np.empty(2 * n + 1, np.int64)
    et = np.empty(2 * n + 1, np.int64)
    pa = np.empty(n + 1, np.int64)
    pb = np.empty(n + 1, np.int64)
    ne = 0
    npend = 0
    for k in range(n):
        a = A[k]
        b = B[k]
        if hi[a] < lo[b]:
            ef[ne] = ev1[a]
            et[ne] = ev0[b]
            ne += 1
        elif hi[b] < lo[a]:
            ef[ne] = ev1[b]
            et[ne] = ev0[a]
            ne += 1
        elif move[a] and move[b]:
            if lazy and min(math.hypot(seg[a, 0] - seg[b, 0], seg[a, 1] - seg[b, 1]),
                            math.hypot(seg[a, 2] - seg[b, 2], seg[a, 3] - seg[b, 3])
                            ) >= two_r + 1e-9:
                pa[npend] = a
                pb[npend] = b
                npend += 1
            else:
                union(parent, ev0[a], ev0[b])
                union(parent, ev1[a], ev1[b])
        else:  # a move within a stay
            m, st = (a, b) if move[a] else (b, a)
            ef[ne] = ev0[st]
            et[ne] = ev0[m]
            ne += 1
            if ev1[st] >= 0:
                ef[ne] = ev1[m]
                et[ne] = ev1[st]
                ne += 1
    return ef[:ne], et[:ne], pa[:npend], pb[:npend]


@nb.njit(cache=True)
def _stable_order(key: np.ndarray, nkey: int) -> np.ndarray:
    """``np.argsort(key, kind="stable")`` of keys in ``[0, nkey)`` (a counting sort)."""
    cnt = np.zeros(nkey + 1, np.int64)
    for k in range(key.shape[0]):
        cnt[key[k] + 1] += 1
    for b in range(nkey):
        cnt[b + 1] += cnt[b]
    o = np.empty(key.shape[0], np.int64)
    for k in range(key.shape[0]):
        o[cnt[key[k]]] = k
        cnt[key[k]] += 1
    return o


@nb.njit(cache=True)
def _earliest(evk: np.ndarray, parent: np.ndarray, ef: np.ndarray, et: np.ndarray,
              w: np.ndarray) -> np.ndarray:
    """Earliest event times (quanta): longest paths over the edges ``ef -> et`` of weight
    ``w`` between the union-find roots, level by level of step index."""
    E = evk.shape[0]
    root = np.empty(E, np.int64)
    for e in range(E):
        root[e] = find(parent, e)
    M = ef.shape[0]
    src = np.empty(M, np.int64)
    dst = np.empty(M, np.int64)
    for k in range(M):
        src[k] = root[ef[k]]
        dst[k] = root[et[k]]
    # edges grouped by the level of their target, sources of lower level first
    lvl_t = evk[dst]
    lvl_s = evk[src]
    K = evk.max() if E else 0
    o = _stable_order(lvl_t * (K + 2) + lvl_s, (K + 1) * (K + 2))
    T = np.zeros(E, np.int64)
    p = 0
    for lv in range(K + 1):
        q0 = p
        while p < M and lvl_t[o[p]] == lv:
            p += 1
        same0 = q0
        for k in range(q0, p):
            j = o[k]
            if lvl_s[j] < lv:
                v = T[src[j]] + w[j]
                if v > T[dst[j]]:
                    T[dst[j]] = v
                same0 = k + 1
        changed = True
        while changed:
            changed = False
            for k in range(same0, p):
                j = o[k]
                v = T[src[j]] + w[j]
                if v > T[dst[j]]:
                    T[dst[j]] = v
                    changed = True
    for e in range(E):
        T[e] = T[root[e]]
    return T


@nb.njit(cache=True)
def _rows(P: np.ndarray, rob: np.ndarray, seg: np.ndarray, ev0: np.ndarray,
          ev1: np.ndarray, T: np.ndarray, q: float, max_spacing: float
          ) -> tuple[np.ndarray, np.ndarray]:
    """(N, R, 2) rows at every event time, subdivided to keep each move per row <=
    ``max_spacing`` (a robot covers at most one quantum of length per quantum), and the
    rows' times (quanta)."""
    N = P.shape[1]
    tmax = T.max()
    used = np.zeros(tmax + 1, np.bool_)
    for e in range(T.shape[0]):
        used[T[e]] = True
    times = np.nonzero(used)[0]
    per = max(1, int(max_spacing / q * (1.0 - 1e-9)))  # quanta per row at most
    cnt = 1
    for k in range(1, times.shape[0]):
        gap = times[k] - times[k - 1]
        cnt += (gap + per - 1) // per
    tt = np.empty(cnt)
    tt[0] = times[0]
    c = 1
    for k in range(1, times.shape[0]):
        gap = times[k] - times[k - 1]
        n = (gap + per - 1) // per
        for m in range(1, n + 1):
            tt[c] = times[k - 1] + gap * m / n
            c += 1
    out = np.empty((N, cnt, 2))
    S = rob.shape[0]
    a = 0
    while a < S:
        i = rob[a]
        b = a
        while b < S and rob[b] == i:
            b += 1
        st = a
        for r in range(cnt):
            t = tt[r]
            while st < b - 1 and ev1[st] >= 0 and T[ev1[st]] < t:
                st += 1
            t0 = T[ev0[st]]
            t1 = T[ev1[st]] if ev1[st] >= 0 else t0
            if t1 > t0 and t > t0:
                f = min(1.0, (t - t0) / (t1 - t0))
                out[i, r, 0] = seg[st, 0] + f * (seg[st, 2] - seg[st, 0])
                out[i, r, 1] = seg[st, 1] + f * (seg[st, 3] - seg[st, 1])
                if f == 1.0:
                    out[i, r, 0] = seg[st, 2]
                    out[i, r, 1] = seg[st, 3]
            else:
                out[i, r, 0] = seg[st, 0]
                out[i, r, 1] = seg[st, 1]
        a = b
    return out, tt


def retime(P: np.ndarray, two_r: float, quantum: float, max_spacing: float,
           lazy: bool = True, max_rounds: int = 12, times: bool = False) -> tuple:
    """Rows (N, R, 2) of the retimed plan of the synchronised step positions ``P``
    (K+1, N, 2), robots of radius ``two_r / 2``, event times in multiples of ``quantum``
    (metres at unit speed); and its makespan (metres); with ``times``, also the rows'
    times (R,) (metres)."""
    P = np.ascontiguousarray(P, dtype=np.float64)
    rob, lo, hi, seg, move, ev0, ev1, evk = _states(P)
    parent = np.arange(len(evk), dtype=np.int64)
    cf, ct, pa, pb = _constraints(rob, lo, hi, seg, move, ev0, ev1, parent, float(two_r),
                                  lazy)
    mv = np.nonzero(move)[0]
    ln = np.hypot(seg[mv, 2] - seg[mv, 0], seg[mv, 3] - seg[mv, 1])
    stay = np.nonzero(~move & (ev1 >= 0))[0]
    ef = np.concatenate([ev0[mv], ev0[stay], cf])
    et = np.concatenate([ev1[mv], ev1[stay], ct])
    w = np.concatenate([np.ceil(ln / quantum - 1e-9).astype(np.int64),
                        np.zeros(len(stay) + len(cf), np.int64)])
    pend = np.ones(len(pa), dtype=bool)
    for _ in range(max_rounds):
        T = _earliest(evk, parent, ef, et, w)
        if not pend.any() or lock_violations(P, rob, seg, ev0, ev1, T.astype(np.float64),
                                              pa, pb, pend, parent, float(two_r)) == 0:
            break
    else:
        for e in np.nonzero(pend)[0]:
            union(parent, ev0[pa[e]], ev0[pb[e]])
            union(parent, ev1[pa[e]], ev1[pb[e]])
        T = _earliest(evk, parent, ef, et, w)
    rows, tt = _rows(P, rob, seg, ev0, ev1, T, float(quantum), float(max_spacing))
    if times:
        return rows, float(T.max()) * quantum, tt * quantum
    return rows, float(T.max()) * quantum


def drop_waits(VX: np.ndarray, coords: np.ndarray) -> np.ndarray:
    """The rows of ``VX`` (vertices per step) in which some robot moved (changed position),
    and the first."""
    P = coords[VX].reshape(VX.shape[0], 2 * VX.shape[1])  # x, y side by side: one reduction
    moved = np.any(P[1:] != P[:-1], axis=1)
    return np.ascontiguousarray(VX[np.concatenate([[True], moved])])


def densify(P: np.ndarray, max_spacing: float) -> np.ndarray:
    """(N, T, 2) paths from the vertex positions ``P`` (t+1, N, 2): each step cut into the
    fewest equal sub-steps that keep every robot's consecutive rows <= ``max_spacing``
    apart, the step's end points kept exactly."""
    if len(P) > 1:
        seg = np.hypot(*(P[1:] - P[:-1]).transpose(2, 0, 1)).max(axis=1)  # (S,)
        K = np.maximum(1, np.ceil(seg / (max_spacing * (1 - 1e-9)))).astype(np.int64)
        step_of = np.repeat(np.arange(len(K)), K)
        offs = np.concatenate([[0], np.cumsum(K)[:-1]])
        frac = (np.arange(K.sum()) - np.repeat(offs, K) + 1) / np.repeat(K, K)
        A = P[step_of]
        B = P[step_of + 1]
        dense = A + frac[:, None, None] * (B - A)
        dense[np.cumsum(K) - 1] = P[1:]  # exact end points of every step
        P = np.concatenate([P[:1], dense])
    return np.ascontiguousarray(P.transpose(1, 0, 2))
