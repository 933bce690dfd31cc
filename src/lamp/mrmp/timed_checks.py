"""The checks of :mod:`lamp.mrmp.timed_repair` against the retimed rows: a robot's motion
over a span of time against every other robot's (in the rows, or along its new way), the
time from which a goal is free for good, each robot's arrival, and the rows with a robot's
new way written in.

Rows: ``X[r, k], Y[r, k]``, robot k's position at time ``tt[r]`` (metres at unit speed),
each robot moving linearly between consecutive rows and still after the last. New ways:
``ways = (rep, WX, WY, WT, wptr, wrob, box)``, way w robot ``wrob[w]``'s (-1: replaced
since) through the points ``WX, WY`` at times ``WT`` (entries ``wptr[w] .. wptr[w + 1]``),
still after its last point, ``box[w]`` its bounding box; ``rep[k]``: robot k follows a
new way (its rows are ignored).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.gspi_kernels import conflict
from lamp.mrmp.neighbours import doubled
from lamp.mrmp.repair_hash import cell, span

__all__ = ["arrivals", "free_time", "gather_rows", "motion_clear", "motion_hits",
           "motion_near", "position_at", "rest_clear", "row_at", "with_way"]


@nb.njit(cache=True)
def row_at(tt: np.ndarray, t: float) -> int:
    """The last row r with ``tt[r] <= t`` (0 before the first)."""
    lo = 0
    hi = tt.shape[0] - 1
    if t >= tt[hi]:
        return hi
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if tt[mid] <= t:
            lo = mid
        else:
            hi = mid - 1
    return lo


@nb.njit(cache=True, inline="always")
def position_at(X: np.ndarray, Y: np.ndarray, tt: np.ndarray, r: int, k: int, t: float
        ) -> tuple[float, float]:
    """Robot k's position at time t within row r (linear to row r + 1; still after the
    last row); exactly the row's position at its ends and when still."""
    R = tt.shape[0]
    if r >= R - 1 or t <= tt[r]:
        return X[r, k], Y[r, k]
    if t >= tt[r + 1]:
        return X[r + 1, k], Y[r + 1, k]
    ax, ay, bx, by = X[r, k], Y[r, k], X[r + 1, k], Y[r + 1, k]
    if ax == bx and ay == by:
        return ax, ay
    f = (t - tt[r]) / (tt[r + 1] - tt[r])
    return ax + f * (bx - ax), ay + f * (by - ay)


@nb.njit(cache=True)
def _ways_clear(i: int, ax: float, ay: float, bx: float, by: float, t0: float, t1: float,
                end_goal: bool, ways: tuple, two_r: float, ends_goal: np.ndarray,
                hit: np.ndarray) -> bool:
    """:func:`motion_clear` against the new ways ``ways = (rep, WX, WY, WT, wptr, wrob,
    box)``: way w is robot ``wrob[w]``'s (-1: replaced since) through the points
    ``WX, WY`` at times ``WT`` (entries ``wptr[w] .. wptr[w + 1]``), still before its
    first point and after its last; ``box[w]``: its bounding box; ``rep[k]``: robot k
    follows a new way. With ``hit`` (N flags; empty: none) every robot in the way is
    marked there and True returned."""
    _, WX, WY, WT, wptr, wrob, box = ways
    lo_x = min(ax, bx) - two_r
    hi_x = max(ax, bx) + two_r
    lo_y = min(ay, by) - two_r
    hi_y = max(ay, by) + two_r
    for w in range(wrob.shape[0]):
        k = wrob[w]
        if k < 0 or k == i or box[w, 0] > hi_x or box[w, 1] < lo_x or box[w, 2] > hi_y \
                or box[w, 3] < lo_y:
            continue
        p0 = wptr[w]
        p1 = wptr[w + 1]
        j = p0 + row_at(WT[p0:p1], t0)
        before = t0 < WT[p0]  # a piece of its own: still at its first point until WT[p0]
        while j < p1:
            e0 = -np.inf if before else WT[j]
            e1 = WT[j] if before else WT[j + 1] if j + 1 < p1 else np.inf
            s0 = max(t0, e0)
            s1 = min(t1, e1)
            if s1 > s0:
                ux, uy = _lerp(WX, WY, WT, j, p1, s0)
                vx, vy = _lerp(WX, WY, WT, j, p1, s1)
                px, py, qx, qy = _piece(ax, ay, bx, by, t0, t1, s0, s1)
                both = end_goal and s1 >= t1 and ends_goal[k] and j == p1 - 1
                if conflict(px, py, qx, qy, ux, uy, vx, vy, two_r, both):
                    if hit.shape[0] == 0:
                        return False
                    hit[k] = True
                    break
            if e1 >= t1:
                break
            if before:
                before = False
            else:
                j += 1
    return True


@nb.njit(cache=True, inline="always")
def _piece(ax: float, ay: float, bx: float, by: float, t0: float, t1: float, s0: float,
           s1: float) -> tuple[float, float, float, float]:
    """The part from time s0 to s1 of the linear motion (ax, ay) at t0 to (bx, by) at
    t1: its two ends (the end exactly (bx, by) when s1 reaches t1)."""
    f0 = (s0 - t0) / (t1 - t0)
    f1 = (s1 - t0) / (t1 - t0)
    qx = bx if f1 >= 1.0 else ax + f1 * (bx - ax)
    qy = by if f1 >= 1.0 else ay + f1 * (by - ay)
    return ax + f0 * (bx - ax), ay + f0 * (by - ay), qx, qy


@nb.njit(cache=True, inline="always")
def _lerp(WX: np.ndarray, WY: np.ndarray, WT: np.ndarray, j: int, p1: int, t: float
          ) -> tuple[float, float]:
    """A way's position at time t in its piece j (still after its last point)."""
    if j + 1 >= p1 or t <= WT[j]:
        return WX[j], WY[j]
    if t >= WT[j + 1]:
        return WX[j + 1], WY[j + 1]
    if WX[j] == WX[j + 1] and WY[j] == WY[j + 1]:
        return WX[j], WY[j]
    f = (t - WT[j]) / (WT[j + 1] - WT[j])
    return WX[j] + f * (WX[j + 1] - WX[j]), WY[j] + f * (WY[j + 1] - WY[j])


@nb.njit(cache=True, inline="always")
def _piece_end(r: int, s0: float, t1: float, tt: np.ndarray) -> tuple[bool, float]:
    """For the piece of a motion (ending at ``t1``) from time ``s0`` in row ``r``: whether
    it lies before the row's time (before the first row every robot stands at it), and
    its end: that time, else the next row's time (none after the last), at most ``t1``."""
    if s0 < tt[r]:
        return True, min(t1, tt[r])
    return False, t1 if r >= tt.shape[0] - 1 else min(t1, tt[r + 1])


@nb.njit(cache=True, inline="always")
def _next_piece(r: int, s0: float, before: bool, t1: float, tt: np.ndarray
                ) -> tuple[bool, int, float]:
    """After the piece from ``s0`` in row ``r`` (``before``: :func:`_piece_end`'s):
    whether the motion ending at ``t1`` is done, else the next piece's row and start."""
    if before:
        return tt[r] >= t1, r, tt[r]
    if r >= tt.shape[0] - 1 or tt[r + 1] >= t1:
        return True, r, s0
    return False, r + 1, tt[r + 1]


@nb.njit(cache=True)
def motion_clear(i: int, ax: float, ay: float, bx: float, by: float, t0: float, t1: float,
                 end_goal: bool, X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple,
                 x0: float, y0: float, cs: float, ny: int, two_r: float,
                 ends_goal: np.ndarray, ways: tuple) -> bool:
    """Whether robot i moving linearly from (ax, ay) at time t0 to (bx, by) at t1
    (``t1 > t0``; a wait when the two are equal) keeps clear of every other robot's
    motion: in the rows ``X, Y`` (times ``tt``), the motion cut at the rows' times, or for
    a robot planned again (``ways``, :func:`_ways_clear`) along its new way, each piece
    checked with :func:`~lamp.mrmp.gspi_kernels.conflict`; ``end_goal``: (bx, by) is
    robot i's goal, and a robot k with ``ends_goal[k]`` is on its goal when at its last
    position."""
    # no flags to mark: an empty view, not an array allocated on every call
    return _motion(i, ax, ay, bx, by, t0, t1, end_goal, X, Y, tt, hh, x0, y0, cs, ny,
                   two_r, ends_goal, ways, ends_goal[:0])


@nb.njit(cache=True)
def motion_hits(i: int, ax: float, ay: float, bx: float, by: float, t0: float, t1: float,
                end_goal: bool, X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple,
                x0: float, y0: float, cs: float, ny: int, two_r: float,
                ends_goal: np.ndarray, ways: tuple, hit: np.ndarray) -> None:
    """:func:`motion_clear`, every robot the motion does not keep clear of marked in
    ``hit`` (N flags) instead."""
    _motion(i, ax, ay, bx, by, t0, t1, end_goal, X, Y, tt, hh, x0, y0, cs, ny, two_r,
            ends_goal, ways, hit)


@nb.njit(cache=True)
def _motion(i: int, ax: float, ay: float, bx: float, by: float, t0: float, t1: float,
            end_goal: bool, X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple,
            x0: float, y0: float, cs: float, ny: int, two_r: float, ends_goal: np.ndarray,
            ways: tuple, hit: np.ndarray) -> bool:
    """:func:`motion_clear`; with ``hit`` (N flags, empty: none) marking every robot
    in the way there and going on, True at the end."""
    if not _ways_clear(i, ax, ay, bx, by, t0, t1, end_goal, ways, two_r, ends_goal, hit):
        return False
    rep = ways[0]
    so = hh[1]
    R = tt.shape[0]
    r = row_at(tt, t0)
    s0 = t0
    while True:
        before, s1 = _piece_end(r, s0, t1, tt)
        if s1 > s0:
            px, py, qx, qy = _piece(ax, ay, bx, by, t0, t1, s0, s1)
            at_end = end_goal and s1 >= t1
            kc = cell(px, py, x0, y0, cs, ny)
            for dx in range(-1, 2):
                p, q = span(r, kc + dx * ny - 1, hh)
                for e in range(p, q):
                    k = so[r, e]
                    if k == i or rep[k]:
                        continue
                    ux, uy = position_at(X, Y, tt, r, k, s0)
                    wx, wy = position_at(X, Y, tt, r, k, s1)
                    both = (at_end and ends_goal[k] and wx == X[R - 1, k]
                            and wy == Y[R - 1, k])
                    if conflict(px, py, qx, qy, ux, uy, wx, wy, two_r, both):
                        if hit.shape[0] == 0:
                            return False
                        hit[k] = True
        done, r, s0 = _next_piece(r, s0, before, t1, tt)
        if done:
            return True


@nb.njit(cache=True)
def gather_rows(i: int, ax: float, ay: float, r0: int, nrows: int, r_end: int, hh: tuple,
                x0: float, y0: float, cs: float, ny: int, rep: np.ndarray, gk: np.ndarray,
                gptr: np.ndarray) -> tuple[np.ndarray, int]:
    """The robots of rows ``r0 + nrows .. r_end`` in the nine cells around (ax, ay),
    robot i and the robots planned again (``rep``) left out, appended to those of rows
    ``r0 .. r0 + nrows - 1``: row r's are ``gk[gptr[r - r0] : gptr[r - r0 + 1]]``
    (``gptr[0] = 0``, ``gptr`` at least ``r_end - r0 + 2`` long). Returns ``gk`` (grown
    when full) and the rows now gathered.

    Every robot whose motion in row r a motion of robot i starting at (ax, ay) does not
    keep clear of is among them: a motion no longer than ``cs - 2r`` less the distance
    a robot moves between rows (the hash's cells, :func:`lamp.mrmp.timed_repair`) comes
    within 2r only of robots within ``cs`` of its start, which lie in these cells
    (:func:`motion_near`)."""
    so = hh[1]
    kc = cell(ax, ay, x0, y0, cs, ny)
    n = gptr[nrows]
    for r in range(r0 + nrows, r_end + 1):
        for dx in range(-1, 2):
            p, q = span(r, kc + dx * ny - 1, hh)
            while n + q - p > gk.shape[0]:
                gk = doubled(gk, n)
            for e in range(p, q):
                k = so[r, e]
                if k != i and not rep[k]:
                    gk[n] = k
                    n += 1
        gptr[r - r0 + 1] = n
    return gk, max(nrows, r_end - r0 + 1)


@nb.njit(cache=True)
def motion_near(i: int, ax: float, ay: float, bx: float, by: float, t0: float, t1: float,
                end_goal: bool, X: np.ndarray, Y: np.ndarray, tt: np.ndarray,
                two_r: float, ends_goal: np.ndarray, ways: tuple, gk: np.ndarray,
                gptr: np.ndarray, r0: int) -> bool:
    """:func:`motion_clear` of a motion starting at (ax, ay) at ``t0`` (row
    ``r0 = row_at(tt, t0)``) against the robots :func:`gather_rows` gathered around
    (ax, ay) for the rows up to ``row_at(tt, t1)`` (``gk, gptr``), instead of each
    piece's cells of the hash: the same answer. Each robot is first measured against
    the piece's start by a bound (the piece's and the robot's row move, summed as
    |dx| + |dy|): farther, it cannot come within 2r in the piece."""
    if not _ways_clear(i, ax, ay, bx, by, t0, t1, end_goal, ways, two_r, ends_goal,
                       ends_goal[:0]):
        return False
    R = tt.shape[0]
    r = r0
    s0 = t0
    while True:
        before, s1 = _piece_end(r, s0, t1, tt)
        if s1 > s0:
            px, py, qx, qy = _piece(ax, ay, bx, by, t0, t1, s0, s1)
            at_end = end_goal and s1 >= t1
            reach = two_r + abs(qx - px) + abs(qy - py) + 1e-7
            still = before or r >= R - 1
            for e in range(gptr[r - r0], gptr[r - r0 + 1]):
                k = gk[e]
                kx, ky = X[r, k], Y[r, k]
                far = reach if still else (reach + abs(X[r + 1, k] - kx)
                                           + abs(Y[r + 1, k] - ky))
                ex, ey = px - kx, py - ky
                if ex * ex + ey * ey > far * far:
                    continue
                ux, uy = position_at(X, Y, tt, r, k, s0)
                wx, wy = position_at(X, Y, tt, r, k, s1)
                both = (at_end and ends_goal[k] and wx == X[R - 1, k]
                        and wy == Y[R - 1, k])
                if conflict(px, py, qx, qy, ux, uy, wx, wy, two_r, both):
                    return False
        done, r, s0 = _next_piece(r, s0, before, t1, tt)
        if done:
            return True


@nb.njit(cache=True)
def rest_clear(i: int, ax: float, ay: float, bx: float, by: float, t0: float, t1: float,
               X: np.ndarray, Y: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
               ny: int, two_r: float, arr: np.ndarray) -> bool:
    """Whether robot i moving linearly from (ax, ay) at t0 to (bx, by) at t1 keeps clear
    (:func:`~lamp.mrmp.gspi_kernels.conflict`) of every other robot k's last position
    from its arrival ``arr[k]`` on, their motions before ignored (a guide for the group
    repair, not a check of the plan)."""
    R = X.shape[0]
    so = hh[1]
    kc = cell(ax, ay, x0, y0, cs, ny)
    for dx in range(-1, 2):
        p, q = span(R - 1, kc + dx * ny - 1, hh)
        for e in range(p, q):
            k = so[R - 1, e]
            if k == i or arr[k] >= t1:
                continue
            s0 = max(t0, arr[k])
            px, py, qx, qy = _piece(ax, ay, bx, by, t0, t1, s0, t1)
            kx, ky = X[R - 1, k], Y[R - 1, k]
            if conflict(px, py, qx, qy, kx, ky, kx, ky, two_r, False):
                return False
    return True


@nb.njit(cache=True)
def free_time(i: int, gx: float, gy: float, X: np.ndarray, Y: np.ndarray, tt: np.ndarray,
               hh: tuple, x0: float, y0: float, cs: float, ny: int, two_r: float,
               ends_goal: np.ndarray, ways: tuple) -> float:
    """The earliest time from which robot i may stay on its goal (gx, gy) to the end
    (inf: never): after the last row, or piece of a new way, whose motion it would not
    keep clear of."""
    free = 0.0
    _, WX, WY, WT, wptr, wrob, _ = ways
    for w in range(wrob.shape[0]):
        k = wrob[w]
        if k < 0 or k == i:
            continue
        for j in range(wptr[w + 1] - 1, wptr[w] - 1, -1):
            last = j == wptr[w + 1] - 1
            e1 = WT[j] + 1.0 if last else WT[j + 1]
            ex, ey = (WX[j], WY[j]) if last else (WX[j + 1], WY[j + 1])
            if conflict(gx, gy, gx, gy, WX[j], WY[j], ex, ey, two_r,
                        ends_goal[k] and last):
                free = max(free, np.inf if last else e1)
                break
    R = tt.shape[0]
    none = (ways[0], WX[:0], WY[:0], WT[:0], wptr[:1], wrob[:0], ways[6][:0])
    for r in range(R - 1, -1, -1):
        t0 = tt[r]
        t1 = tt[r + 1] if r < R - 1 else tt[r] + 1.0
        if not motion_clear(i, gx, gy, gx, gy, t0, t1, True, X, Y, tt, hh, x0, y0, cs, ny,
                            two_r, ends_goal, none):
            return max(free, np.inf if r == R - 1 else t1)
    return free


@nb.njit(cache=True)
def arrivals(X: np.ndarray, Y: np.ndarray, tt: np.ndarray) -> np.ndarray:
    """Each robot's arrival: the time of the first row from which it no longer moves."""
    R, N = X.shape
    out = np.zeros(N)
    for k in range(N):
        r = R - 1
        while r > 0 and X[r - 1, k] == X[R - 1, k] and Y[r - 1, k] == Y[R - 1, k]:
            r -= 1
        out[k] = tt[r]
    return out


@nb.njit(cache=True)
def with_way(X: np.ndarray, Y: np.ndarray, tt: np.ndarray, i: int, wx: np.ndarray,
              wy: np.ndarray, wt: np.ndarray, max_spacing: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows with robot i's motion replaced by the way through (wx, wy) at times wt
    (still after its last point): rows inserted at the way's times, and within its moves
    so that it moves at most ``max_spacing`` between rows; the others at their exact
    positions there; rows after the last motion of any robot dropped."""
    R, N = X.shape
    nw = wt.shape[0]
    extra = np.empty(0)
    cnt = 0
    for k in range(nw - 1):
        ln = math.hypot(wx[k + 1] - wx[k], wy[k + 1] - wy[k])
        cnt += max(1, int(math.ceil(ln / (max_spacing * (1.0 - 1e-9)))))
    extra = np.empty(cnt + 1)
    c = 0
    extra[c] = wt[0]
    c += 1
    for k in range(nw - 1):
        ln = math.hypot(wx[k + 1] - wx[k], wy[k + 1] - wy[k])
        pieces = max(1, int(math.ceil(ln / (max_spacing * (1.0 - 1e-9)))))
        for p in range(1, pieces + 1):
            extra[c] = wt[k] + (wt[k + 1] - wt[k]) * p / pieces if p < pieces else wt[k + 1]
            c += 1
    allt = np.concatenate((tt, extra))
    allt.sort()
    times = np.empty(allt.shape[0])
    nt = 0
    for k in range(allt.shape[0]):
        if nt == 0 or allt[k] > times[nt - 1] + 1e-9:
            times[nt] = allt[k]
            nt += 1
    times = times[:nt]
    NX = np.empty((nt, N))
    NY = np.empty((nt, N))
    r = 0
    w = 0
    for a in range(nt):
        s = times[a]
        while r < R - 1 and tt[r + 1] <= s + 1e-9:
            r += 1
        for k in range(N):
            if abs(s - tt[r]) <= 1e-9:
                NX[a, k], NY[a, k] = X[r, k], Y[r, k]
            else:
                NX[a, k], NY[a, k] = position_at(X, Y, tt, r, k, s)
        while w < nw - 1 and wt[w + 1] <= s + 1e-9:
            w += 1
        if w >= nw - 1 or abs(s - wt[w]) <= 1e-9:
            NX[a, i], NY[a, i] = wx[w], wy[w]
        else:
            f = (s - wt[w]) / (wt[w + 1] - wt[w])
            if wx[w] == wx[w + 1] and wy[w] == wy[w + 1]:
                NX[a, i], NY[a, i] = wx[w], wy[w]
            else:
                NX[a, i] = wx[w] + f * (wx[w + 1] - wx[w])
                NY[a, i] = wy[w] + f * (wy[w + 1] - wy[w])
    last = 0
    for a in range(1, nt):
        for k in range(N):
            if NX[a, k] != NX[a - 1, k] or NY[a, k] != NY[a - 1, k]:
                last = a
                break
    return NX[: last + 1].copy(), NY[: last + 1].copy(), times[: last + 1].copy()
