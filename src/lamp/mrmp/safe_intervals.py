"""Safe intervals of a vertex for :mod:`lamp.mrmp.timed_sipp`: the times, in whole quanta,
between which a robot may wait on a point while the other robots follow the retimed rows
and the new ways (:mod:`lamp.mrmp.timed_checks`).

The rule is Gspi's (:func:`lamp.mrmp.gspi_kernels.conflict`): over a piece of time in
which both move linearly, the distance of two robots never falls below ``min(2r, the
distance at the piece's start)``. For a robot waiting at a point p and another robot k
moving linearly over a piece ``[e0, e1]``, the distance ``d(s)`` is convex in s, with its
minimum at ``s*`` (clamped to the piece). A wait over ``[s0, s1]`` inside the piece is
refused exactly when ``s0 < s*`` and ``s1 > a``, where ``a`` is the first time in the
piece at which ``d < 2r`` (``e0`` when k starts closer): before ``a`` the distance is at
least 2r, and from within 2r the distance may only grow, which it does from ``s*`` on.
So the wait over ``[s0, s1]`` is refused by k's piece exactly when it meets the open
interval ``(a, s*)``; cut at other times (the pieces of
:func:`~lamp.mrmp.timed_checks.motion_clear` are cut at every row's time) the answer is
the same, so a piece may be as long as k's velocity stays the same: the rows are merged
into such segments once (:func:`segment_index`), the new ways taken piece by piece. With
the rule's tolerance :data:`TOL`, ``a`` is when k comes within ``2r - TOL`` and ``s*``
when it is within ``TOL`` of its closest (:func:`unsafe_span`). A robot standing still
never refuses a wait (its distance is constant), nor does one after its last row or way
point.

The unit wait from t to t + 1 quanta is refused when it meets one of these intervals;
the safe intervals are the maximal runs of whole times joined by unit waits that are not
refused (:func:`runs_of`): a robot that reaches one may wait in it to any later time of
it. Each starts at its first time at which no other robot is within 2r (a run of times
with no wait possible either side is dropped with them): a move arriving while another
robot is within 2r of its end is refused, unless the two were within 2r when it started
(never in a plan whose robots start 2r apart) or both end there on goals (the search
does not drop such times on the robot's goal). The answers are of floating-point
arithmetic (times within 1e-9 quanta of an end taken as refused);
:mod:`lamp.mrmp.timed_sipp` checks every wait and move it keeps with
:func:`~lamp.mrmp.timed_checks.motion_near` as well.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["TOL", "blocked_waits", "runs_of", "segment_index", "unsafe_span"]

#: :func:`~lamp.mrmp.gspi_kernels.conflict`'s tolerance: a motion is refused when the
#: distance falls more than this below what the rule allows.
TOL = 1e-9


@nb.njit(cache=True, inline="always")
def unsafe_span(px: float, py: float, ax: float, ay: float, bx: float, by: float,
                e0: float, e1: float, two_r: float) -> tuple[float, float, float, float]:
    """For a wait at (px, py) and a robot moving linearly from (ax, ay) at ``e0`` to
    (bx, by) at ``e1`` (still when they are equal; ``e1`` may be inf then): the open
    interval ``(a, s)`` that the waits it refuses meet, and the open interval of times
    at which it is within 2r (module docstring); an interval is empty when its ends are
    not in order. With :func:`~lamp.mrmp.gspi_kernels.conflict`'s tolerance
    (:data:`TOL`): ``a`` is when it comes within ``2r - TOL`` (``e0`` when it starts
    within 2r), ``s`` when it is within ``TOL`` of its closest in the piece."""
    dx, dy = ax - px, ay - py
    ux, uy = bx - ax, by - ay
    uu = ux * ux + uy * uy
    dd = dx * dx + dy * dy
    rr = two_r * two_r
    if uu == 0.0 or not e1 > e0:
        return (0.0, 0.0, e0, e1) if dd < rr and e1 > e0 else (0.0, 0.0, 0.0, 0.0)
    du = dx * ux + dy * uy
    tau = min(1.0, max(0.0, -du / uu))  # the closest approach, as a share of the piece
    cx, cy = dx + tau * ux, dy + tau * uy
    dm = math.sqrt(cx * cx + cy * cy)
    if dm >= two_r:
        return 0.0, 0.0, 0.0, 0.0
    inside0 = 0.0 if dd < rr else (-du - math.sqrt(max(du * du - uu * (dd - rr), 0.0))) / uu
    leave = min(1.0, (-du + math.sqrt(max(du * du - uu * (dd - rr), 0.0))) / uu)
    if dd < rr:
        enter = 0.0
    elif dm < two_r - TOL:
        lim = (two_r - TOL) * (two_r - TOL)
        enter = (-du - math.sqrt(max(du * du - uu * (dd - lim), 0.0))) / uu
    else:
        enter = 1.0  # never below 2r - TOL: no wait refused
    near = (dm + TOL) * (dm + TOL)
    close = 0.0 if dd <= near else (-du - math.sqrt(max(du * du - uu * (dd - near), 0.0))) / uu
    w = e1 - e0
    return (e0 + max(enter, 0.0) * w, e0 + min(close, tau) * w, e0 + max(inside0, 0.0) * w,
            e0 + max(leave, tau) * w)


@nb.njit(cache=True, inline="always")
def _mark(a: float, s: float, c: float, b: float, q: float, t_lo: int, blk: np.ndarray,
          ins: np.ndarray) -> None:
    """Mark in ``blk`` (entry ``t - t_lo``) every unit wait ``[t q, (t + 1) q]`` that
    meets the open interval ``(a, s)``, and in ``ins`` every time t with ``c < t q <
    b``, with a margin of 1e-9 quanta (refused rather than let through: the caller
    checks what it keeps)."""
    n = blk.shape[0]
    if a < s:
        lo = max(t_lo, int(math.floor(a / q - 1.0 - 1e-9)) + 1)
        hi = min(t_lo + n, int(math.ceil(s / q + 1e-9)))
        for t in range(lo, hi):
            blk[t - t_lo] = True
    c = max(c, (t_lo - 2) * q)  # a still robot's times may be infinite
    if c < b:
        lo = max(t_lo, int(math.floor(c / q - 1e-9)) + 1)
        hi = t_lo + n if b > (t_lo + n) * q else int(math.ceil(b / q + 1e-9))
        for t in range(lo, hi):
            ins[t - t_lo] = True


@nb.njit(cache=True)
def blocked_waits(i: int, px: float, py: float, t_lo: int, q: float, segs: tuple,
                  two_r: float, ways: tuple, blk: np.ndarray, ins: np.ndarray) -> None:
    """Mark in ``blk`` (entry ``t - t_lo``, for ``t_lo <= t < t_lo + len(blk)``) the unit
    waits of robot i at (px, py) that another robot's motion refuses, and in ``ins`` the
    times at which another robot is within 2r of it: along the rows' segments ``segs``
    (:func:`segment_index`) but for the robots planned again (``ways[0]``), and along
    the new ways (:mod:`lamp.mrmp.timed_checks`)."""
    rep, WX, WY, WT, wptr, wrob, box = ways
    sk, sv, ptr, idx, gx0, gy0, gs, gnx, gny = segs
    t0 = t_lo * q
    t1 = (t_lo + blk.shape[0]) * q
    a = min(max(int((px - gx0) / gs), 0), gnx - 1)
    b = min(max(int((py - gy0) / gs), 0), gny - 1)
    for e in range(ptr[a * gny + b], ptr[a * gny + b + 1]):
        s = idx[e]
        k = sk[s]
        if k == i or rep[k] or sv[s, 1] <= t0 or sv[s, 0] >= t1:
            continue
        ea, es, ec, eb = unsafe_span(px, py, sv[s, 2], sv[s, 3], sv[s, 4], sv[s, 5],
                                     sv[s, 0], sv[s, 1], two_r)
        _mark(ea, es, ec, eb, q, t_lo, blk, ins)
    for w in range(wrob.shape[0]):
        k = wrob[w]
        if k < 0 or k == i or box[w, 0] > px + two_r or box[w, 1] < px - two_r \
                or box[w, 2] > py + two_r or box[w, 3] < py - two_r:
            continue
        p0, p1 = wptr[w], wptr[w + 1]
        for j in range(p0 - 1, p1):  # still before its first point and after its last
            e0 = -np.inf if j < p0 else WT[j]
            e1 = WT[j + 1] if j + 1 < p1 else np.inf
            if e1 <= t0 or e0 >= t1:
                continue
            c0 = max(j, p0)
            c1 = min(j + 1, p1 - 1)
            ea, es, ec, eb = unsafe_span(px, py, WX[c0], WY[c0], WX[c1], WY[c1], e0, e1,
                                         two_r)
            _mark(ea, es, ec, eb, q, t_lo, blk, ins)


@nb.njit(cache=True)
def runs_of(blk: np.ndarray, ins: np.ndarray, t_lo: int, lo: np.ndarray, hi: np.ndarray,
            n: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The safe intervals of the times ``t_lo .. t_lo + len(blk) - 1`` (``blk``: the
    refused unit waits, ``ins``: the times within 2r of another robot,
    :func:`blocked_waits`) appended to ``lo, hi`` (first and last time of each, ``n``
    entries before; grown when full), in time order, each from its first time not in
    ``ins`` (none that has none); returns them and their count."""
    T = blk.shape[0]
    start = 0
    for t in range(T):
        if not (blk[t] or t == T - 1):
            continue
        while start <= t and ins[start]:
            start += 1
        if start <= t:
            if n == lo.shape[0]:
                lo2 = np.empty(2 * n + 16, np.int64)
                hi2 = np.empty(2 * n + 16, np.int64)
                lo2[:n] = lo[:n]
                hi2[:n] = hi[:n]
                lo, hi = lo2, hi2
            lo[n], hi[n] = t_lo + start, t_lo + t
            n += 1
        start = t + 1
    return lo, hi, n



@nb.njit(cache=True)
def _segments(X: np.ndarray, Y: np.ndarray, tt: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Every robot's rows as segments of constant velocity: a robot's consecutive pieces
    merged while their velocity stays within 1e-9 of the first's (still ones too), and
    the still one after the last row (to inf). Returns each segment's robot and its
    ``(t0, t1, x0, y0, x1, y1)``, in the order in which they end (ties by robot)."""
    R, N = X.shape
    sk = np.empty(64 + 8 * N, np.int64)
    sv = np.empty((64 + 8 * N, 6))
    start = np.zeros(N, np.int64)  # each robot's segment so far: from this row
    vx = np.zeros(N)
    vy = np.zeros(N)
    n = 0
    for r in range(R):
        d = tt[r + 1] - tt[r] if r < R - 1 else 0.0
        inv = 1.0 / d if d > 0.0 else np.inf
        for k in range(N):
            if r < R - 1:
                ux = (X[r + 1, k] - X[r, k]) * inv
                uy = (Y[r + 1, k] - Y[r, k]) * inv
                if r == 0 or (abs(ux - vx[k]) <= 1e-9 and abs(uy - vy[k]) <= 1e-9):
                    if r == 0:
                        vx[k], vy[k] = ux, uy
                    continue
            if n + 2 > sk.shape[0]:
                sk2 = np.empty(2 * n, np.int64)
                sv2 = np.empty((2 * n, 6))
                sk2[:n] = sk[:n]
                sv2[:n] = sv[:n]
                sk, sv = sk2, sv2
            if r > 0:  # the segment from its start to this row
                a = start[k]
                sk[n] = k
                sv[n, 0], sv[n, 1] = tt[a], tt[r]
                sv[n, 2], sv[n, 3], sv[n, 4], sv[n, 5] = X[a, k], Y[a, k], X[r, k], Y[r, k]
                n += 1
            start[k] = r
            if r < R - 1:
                vx[k], vy[k] = ux, uy
            else:  # still after the last row
                sk[n] = k
                sv[n, 0], sv[n, 1] = tt[r], np.inf
                sv[n, 2], sv[n, 3], sv[n, 4], sv[n, 5] = X[r, k], Y[r, k], X[r, k], Y[r, k]
                n += 1
    return sk[:n], sv[:n]


@nb.njit(cache=True)
def segment_index(X: np.ndarray, Y: np.ndarray, tt: np.ndarray, two_r: float, x0: float,
                  y0: float, x1: float, y1: float) -> tuple:
    """The rows' segments (:func:`_segments`) on a grid of cells of side ``2 two_r``
    over [x0, x1] x [y0, y1]: each in every cell its bounding box grown by ``two_r``
    meets, so that the segments that come within 2r of a point are among those of its
    cell. Returns ``(robot, segment, ptr, idx, x0, y0, cell side, cells along x and
    along y)``: cell ``(a, b)`` is ``c = a ny + b``, its segments are ``idx[ptr[c]:ptr[c + 1]]``, in the order of :func:`_segments`."""
    sk, sv = _segments(X, Y, tt)
    gs = 2.0 * two_r
    nx = int((x1 - x0) / gs) + 1
    ny = int((y1 - y0) / gs) + 1
    ptr = np.zeros(nx * ny + 1, np.int64)
    for s in range(sk.shape[0]):
        a0, a1, b0, b1 = _box_cells(sv, s, two_r, x0, y0, gs, nx, ny)
        for a in range(a0, a1 + 1):
            for b in range(b0, b1 + 1):
                ptr[a * ny + b + 1] += 1
    for c in range(nx * ny):
        ptr[c + 1] += ptr[c]
    idx = np.empty(ptr[nx * ny], np.int64)
    fill = ptr[:-1].copy()
    for s in range(sk.shape[0]):
        a0, a1, b0, b1 = _box_cells(sv, s, two_r, x0, y0, gs, nx, ny)
        for a in range(a0, a1 + 1):
            for b in range(b0, b1 + 1):
                idx[fill[a * ny + b]] = s
                fill[a * ny + b] += 1
    return sk, sv, ptr, idx, x0, y0, gs, nx, ny


@nb.njit(cache=True, inline="always")
def _box_cells(sv: np.ndarray, s: int, grow: float, x0: float, y0: float, gs: float,
               nx: int, ny: int) -> tuple[int, int, int, int]:
    """The first and last cell along x and along y that segment s's bounding box,
    grown by ``grow``, meets (clamped to the grid)."""
    a0 = min(max(int((min(sv[s, 2], sv[s, 4]) - grow - x0) / gs), 0), nx - 1)
    a1 = min(max(int((max(sv[s, 2], sv[s, 4]) + grow - x0) / gs), 0), nx - 1)
    b0 = min(max(int((min(sv[s, 3], sv[s, 5]) - grow - y0) / gs), 0), ny - 1)
    b1 = min(max(int((max(sv[s, 3], sv[s, 5]) + grow - y0) / gs), 0), ny - 1)
    return a0, a1, b0, b1
