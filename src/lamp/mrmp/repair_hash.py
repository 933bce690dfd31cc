"""The spatial hash of :mod:`lamp.mrmp.repair`: where every robot is at each row.

Per row ``t``, the robots sorted by the key of their position's cell (``sk[t]`` the keys,
``so[t]`` the robots), cells wider than the distance within which two robots can
conflict in one row, and a table ``first[t, k]``: the first entry of row t whose key is
at least ``k``. The robots of three consecutive keys (a column of three cells) are then
the entries ``first[t, k0] .. first[t, k0 + 3]``: two reads, where a binary search over
the row took about a third of a repair's time at 400 robots. Rows whose table would be
too large (:data:`TABLE_ENTRIES`, huge maps with many rows) fall back to the binary
search; both give the same entries.

:func:`move_ok` is the repair's check of one motion against every other robot's motion in
its row, with Gspi's own rule (:func:`lamp.mrmp.gspi_kernels.conflict`). The repair's
search checks the moves out of one vertex in one row against the same robots:
:func:`gather` collects them once (only those whose motion comes within ``2r`` plus the
longest move of the vertex: the others keep ``2r`` from any move out of it), and
:func:`clear_of` checks a move against them, in the same order, with the same answer.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from lamp.geometry.kernels import point_segment_distance
from lamp.mrmp.gspi_kernels import conflict

__all__ = ["TABLE_ENTRIES", "build_hash", "cell", "clear_of", "gather", "hash_rows", "move_ok",
           "set_key", "span"]

#: The most entries (rows x cells) of the ``first`` table; beyond, binary search.
TABLE_ENTRIES = 1 << 23


@nb.njit(cache=True)
def cell(x: float, y: float, x0: float, y0: float, cs: float, ny: int) -> int:
    """The key of the cell of (x, y)."""
    return (int((x - x0) / cs) + 1) * ny + int((y - y0) / cs) + 1


@nb.njit(cache=True)
def build_hash(VX: np.ndarray, coords: np.ndarray, cs: float, table: bool
               ) -> tuple[tuple, float, float, int]:
    """The hash ``(sk, so, first)`` of the rows ``VX`` (vertices, positions ``coords``),
    cells of side ``cs``, and the cells' origin and row stride (x0, y0, ny); ``first``
    empty when not ``table`` or too large."""
    K1, N = VX.shape
    X = np.empty((K1, N))
    Y = np.empty((K1, N))
    for t in range(K1):
        for k in range(N):
            X[t, k] = coords[VX[t, k], 0]
            Y[t, k] = coords[VX[t, k], 1]
    x0 = coords[:, 0].min()
    y0 = coords[:, 1].min()
    hh, ny = hash_rows(X, Y, x0, y0, coords[:, 0].max(), coords[:, 1].max(), cs, table)
    return hh, x0, y0, ny


@nb.njit(cache=True)
def hash_rows(X: np.ndarray, Y: np.ndarray, x0: float, y0: float, x1: float, y1: float,
              cs: float, table: bool) -> tuple[tuple, int]:
    """The hash ``(sk, so, first)`` of the positions (``X[t, k]``, ``Y[t, k]``) of rows
    t, all of them and all positions keyed later within [x0, x1] x [y0, y1]; and the row
    stride ``ny`` of the keys."""
    K1, N = X.shape
    ny = int((y1 - y0) / cs) + 3
    ncell = (int((x1 - x0) / cs) + 4) * ny + 4
    sk = np.empty((K1, N), np.int64)
    so = np.empty((K1, N), np.int64)
    inside = True
    for t in range(K1):
        for k in range(N):
            kk = cell(X[t, k], Y[t, k], x0, y0, cs, ny)
            sk[t, k] = kk
            inside &= 0 <= kk < ncell
    table = table and K1 * ncell <= TABLE_ENTRIES
    if table and inside:  # counting sorts, whose running counts are the table
        return (sk, so, _counting_sorts(sk, so, ncell)), ny
    for t in range(K1):
        o = np.argsort(sk[t], kind="mergesort")
        so[t] = o
        sk[t] = sk[t][o]
    if table:
        first = np.empty((K1, ncell), np.int32)
        for t in range(K1):
            p = 0
            for kk in range(ncell):
                while p < N and sk[t, p] < kk:
                    p += 1
                first[t, kk] = p
    else:
        first = np.zeros((0, 0), np.int32)
    return (sk, so, first), ny


@nb.njit(cache=True)
def _counting_sorts(sk: np.ndarray, so: np.ndarray, ncell: int) -> np.ndarray:
    """Sort each row of the keys ``sk`` (all in ``[0, ncell)``) in place, stably (the
    order of a stable argsort), with the order in ``so``; returns the table
    ``first[t, kk]``: row t's entries with keys below kk."""
    K1, N = sk.shape
    first = np.zeros((K1, ncell), np.int32)
    key = np.empty(N, np.int64)
    for t in range(K1):
        cnt = first[t]
        for k in range(N):
            key[k] = sk[t, k]
            cnt[key[k]] += 1
        p = 0
        for kk in range(ncell):  # entries up to key kk
            p += cnt[kk]
            cnt[kk] = p
        for k in range(N - 1, -1, -1):  # from the back: each count ends up below its key
            q = cnt[key[k]] - 1
            so[t, q] = k
            sk[t, q] = key[k]
            cnt[key[k]] = q
    return first


@nb.njit(cache=True, inline="always")
def span(t: int, k0: int, hh: tuple) -> tuple[int, int]:
    """The entries of row t with keys k0 .. k0 + 2."""
    sk, _, first = hh
    if first.shape[0] > 0:
        return first[t, k0], first[t, k0 + 3]
    p = np.searchsorted(sk[t], k0)
    q = p
    N = sk.shape[1]
    while q < N and sk[t, q] <= k0 + 2:
        q += 1
    return p, q


@nb.njit(cache=True)
def move_ok(i: int, t: int, a: int, b: int, VX: np.ndarray, coords: np.ndarray, gv0: int,
            hh: tuple, x0: float, y0: float, cs: float, ny: int, two_r: float,
            skip: np.ndarray, found: np.ndarray) -> bool:
    """Whether robot i moving from vertex a to b in step t (row t -> t+1) keeps clear of
    the motion of every other robot not in ``skip`` in that step; with a non-empty
    ``found``, every robot it does not keep clear of is marked there instead."""
    so = hh[1]
    ax = coords[a, 0]
    ay = coords[a, 1]
    bx = coords[b, 0]
    by = coords[b, 1]
    kc = cell(ax, ay, x0, y0, cs, ny)
    b_goal = b >= gv0
    for dx in range(-1, 2):  # the three cells of a column have consecutive keys
        p, q = span(t, kc + dx * ny - 1, hh)
        for e in range(p, q):
            k = so[t, e]
            if k == i or skip[k]:
                continue
            u = VX[t, k]
            w = VX[t + 1, k]
            if conflict(ax, ay, bx, by, coords[u, 0], coords[u, 1], coords[w, 0],
                        coords[w, 1], two_r, b_goal and w >= gv0):
                if found.shape[0] == 0:
                    return False
                found[k] = True
    return True


@nb.njit(cache=True)
def set_key(t: int, i: int, key: int, hh: tuple) -> None:
    """Move robot i's entry of row t to ``key`` (the sorted arrays and the table)."""
    sk, so, first = hh
    N = sk.shape[1]
    p = 0
    while so[t, p] != i:
        p += 1
    old = sk[t, p]
    for q in range(p, N - 1):  # out, then in at its place (keys ascending)
        sk[t, q] = sk[t, q + 1]
        so[t, q] = so[t, q + 1]
    q = N - 1
    while q > 0 and sk[t, q - 1] > key:
        sk[t, q] = sk[t, q - 1]
        so[t, q] = so[t, q - 1]
        q -= 1
    sk[t, q] = key
    so[t, q] = i
    if first.shape[0] > 0:
        for kk in range(old + 1, key + 1):  # one entry fewer below these keys
            first[t, kk] -= 1
        for kk in range(key + 1, old + 1):  # one more
            first[t, kk] += 1


@nb.njit(cache=True)
def gather(i: int, t: int, a: int, VX: np.ndarray, coords: np.ndarray, gv0: int, hh: tuple,
           x0: float, y0: float, cs: float, ny: int, reach: float, skip: np.ndarray,
           buf: np.ndarray) -> int:
    """The robots (but i and those in ``skip``) whose motion in step t comes within
    ``reach`` of vertex a, in :func:`move_ok`'s order: their motions' ends in
    ``buf[:n, :4]``, ``buf[:n, 4]`` 1 where the motion ends on a goal. Returns n."""
    so = hh[1]
    ax = coords[a, 0]
    ay = coords[a, 1]
    kc = cell(ax, ay, x0, y0, cs, ny)
    n = 0
    for dx in range(-1, 2):
        p, q = span(t, kc + dx * ny - 1, hh)
        for e in range(p, q):
            k = so[t, e]
            if k == i or skip[k]:
                continue
            u = VX[t, k]
            w = VX[t + 1, k]
            cx, cy, dx_, dy_ = coords[u, 0], coords[u, 1], coords[w, 0], coords[w, 1]
            if point_segment_distance(ax, ay, cx, cy, dx_, dy_) >= reach:
                continue
            buf[n, 0] = cx
            buf[n, 1] = cy
            buf[n, 2] = dx_
            buf[n, 3] = dy_
            buf[n, 4] = 1.0 if w >= gv0 else 0.0
            n += 1
    return n


@nb.njit(cache=True, inline="always")
def clear_of(ax: float, ay: float, bx: float, by: float, b_goal: bool, buf: np.ndarray,
             n: int, two_r: float) -> bool:
    """Whether the motion a -> b keeps clear of the ``n`` motions :func:`gather` found
    (:func:`move_ok`'s answer when b is at most the longest move from a)."""
    for q in range(n):
        if conflict(ax, ay, bx, by, buf[q, 0], buf[q, 1], buf[q, 2], buf[q, 3], two_r,
                    b_goal and buf[q, 4] > 0.5):
            return False
    return True
