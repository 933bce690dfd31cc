"""Neighbour lists of points from a spatial hash (Gspi's robot-robot checks and swaps)."""

from __future__ import annotations

import numba as nb
import numpy as np

__all__ = ["ALL_PAIRS_BELOW", "cell_hash", "cell_start", "cell_starts", "doubled",
           "neighbour_lists", "within"]

#: Teams smaller than this swap goals over all pairs and check all pairs (no hashing).
ALL_PAIRS_BELOW = 32


@nb.njit(cache=True)
def cell_hash(px: np.ndarray, py: np.ndarray, cs: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The spatial hash of points (``px``, ``py``) on cells of side ``cs``: each point's
    cell key, the points in key order (stable), the sorted keys, and the keys' row
    stride ``ny`` (the cell at ``dx, dy`` from key ``k`` is ``k + dx * ny + dy``; a
    margin of one cell round the points keeps every neighbour key valid)."""
    n = px.shape[0]
    x0 = px.min()
    y0 = py.min()
    ny = int((py.max() - y0) / cs) + 3
    key = np.empty(n, dtype=np.int64)
    for i in range(n):
        key[i] = (int((px[i] - x0) / cs) + 1) * ny + int((py[i] - y0) / cs) + 1
    order = np.argsort(key, kind="mergesort")
    return key, order, key[order], ny


@nb.njit(cache=True)
def cell_starts(skey: np.ndarray, ny: int) -> tuple[bool, np.ndarray]:
    """For :func:`cell_hash`'s sorted keys ``skey``: (True, each key's first entry in
    ``skey``) when the keys span few cells (at most ``64 n + 65536``), else (False, an
    unused array): :func:`cell_start` then finds an entry by binary search."""
    n = skey.shape[0]
    ncell = skey[n - 1] + ny + 2 if n else 0
    table = ncell <= 64 * n + 65536
    first = np.zeros(ncell + 1 if table else 1, dtype=np.int64)
    if table:
        p = 0
        for kk in range(ncell + 1):
            while p < n and skey[p] < kk:
                p += 1
            first[kk] = p
    return table, first


@nb.njit(cache=True, inline="always")
def cell_start(kk: int, skey: np.ndarray, table: bool, first: np.ndarray) -> int:
    """The first entry of key ``kk`` in ``skey`` (``cell_starts``'s answer)."""
    return first[kk] if table else np.searchsorted(skey, kk)


@nb.njit(cache=True)
def doubled(x: np.ndarray, n: int) -> np.ndarray:
    """A buffer of twice ``x``'s length holding its first ``n`` entries (growing an array
    filled up to ``n`` inside a compiled loop)."""
    y = np.empty(2 * x.shape[0], x.dtype)
    y[:n] = x[:n]
    return y


@nb.njit(cache=True)
def neighbour_lists(px: np.ndarray, py: np.ndarray, radius: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """CSR lists (ptr, idx): for each point i, the other points within ``radius`` (all of
    them when ``radius`` is inf or there are fewer than :data:`ALL_PAIRS_BELOW`), in
    increasing index order. A spatial hash (cells of side ``radius``, points sorted by
    cell; the 9 cells around a point are three runs of consecutive keys, each run's
    entries found in a table of the cells, or by binary search when the cells are many)
    keeps it O(N log N + pairs)."""
    N = px.shape[0]
    ptr = np.zeros(N + 1, dtype=np.int64)
    if N < ALL_PAIRS_BELOW or not radius < np.inf:
        idx = np.empty(N * (N - 1), dtype=np.int64)
        q = 0
        for i in range(N):
            for j in range(N):
                if j != i:
                    idx[q] = j
                    q += 1
            ptr[i + 1] = q
        return ptr, idx
    key, order, skey, ny = cell_hash(px, py, max(radius, 1e-9))
    table, first = cell_starts(skey, ny)
    r2 = radius * radius
    buf = np.empty(64, dtype=np.int64)
    cnt = np.zeros(N, dtype=np.int64)
    out = np.empty(max(16, 8 * N), dtype=np.int64)
    q = 0
    for i in range(N):
        n = 0
        for dx in range(-1, 2):
            # the three cells dy = -1, 0, 1 have consecutive keys: one range of entries
            kk = key[i] + dx * ny
            for p in range(cell_start(kk - 1, skey, table, first),
                           cell_start(kk + 2, skey, table, first)):
                j = order[p]
                if j == i:
                    continue
                ex = px[j] - px[i]
                ey = py[j] - py[i]
                if ex * ex + ey * ey <= r2:
                    if n == buf.shape[0]:
                        nb_ = np.empty(2 * n, dtype=np.int64)
                        nb_[:n] = buf
                        buf = nb_
                    buf[n] = j
                    n += 1
        if q + n > out.shape[0]:
            grown = np.empty(2 * (q + n), dtype=np.int64)
            grown[:q] = out[:q]
            out = grown
        for a in range(n):  # insertion sort into place (a few dozen at most)
            v = buf[a]
            b = q + a
            while b > q and out[b - 1] > v:
                out[b] = out[b - 1]
                b -= 1
            out[b] = v
        q += n
        cnt[i] = n
        ptr[i + 1] = q
    return ptr, out[:q]


@nb.njit(cache=True)
def within(ptr: np.ndarray, idx: np.ndarray, px: np.ndarray, py: np.ndarray,
           radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The lists (ptr, idx) cut to the points within ``radius`` (order kept): the lists of
    a smaller radius from those of a larger one, as :func:`neighbour_lists` gives them."""
    N = ptr.shape[0] - 1
    r2 = radius * radius
    optr = np.zeros(N + 1, dtype=np.int64)
    oidx = np.empty(idx.shape[0], dtype=np.int64)
    q = 0
    for i in range(N):
        for k in range(ptr[i], ptr[i + 1]):
            j = idx[k]
            ex = px[j] - px[i]
            ey = py[j] - py[i]
            if ex * ex + ey * ey <= r2:
                oidx[q] = j
                q += 1
        optr[i + 1] = q
    return optr, oidx[:q]
