"""Reads of Gspi's heuristic values compiled into the hot loops (steps, repair).

A compiled call of :func:`lamp.mrmp.goal_distances.hval` passes the whole
:class:`~lamp.mrmp.goal_distances.GoalDistances` tuple and costs about 0.3 us; a value
already settled in the goal's window, or memoised for a special vertex, is read here
in a few nanoseconds when the caller reads the window's arrays once. The values are
``hval``'s, bit for bit (``tests/test_mrmp_coarse.py``).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.goal_distances import EPS, expand_to, hval

__all__ = ["goal_views", "hval_below", "hval_fast", "hval_in", "read_in", "read_settled"]


@nb.njit(cache=True, inline="always")
def read_settled(m: int, v: int, V: int, hs: tuple, dd: np.ndarray, dn: np.ndarray,
                 a0: int, b0: int, na: int, nbw: int) -> float:
    """Goal m's value at vertex v when already settled (memoised for a special vertex),
    else -1; ``dd``/``dn``/``a0, b0, na, nbw``: goal m's window arrays and extent, read
    once by the caller (a :func:`hval` call per value costs about 0.3 us, forty times
    this; after one, the window may have grown: read them again)."""
    return read_in(m, v, V, hs[11], hs[12], hs[9], hs[10], dd, dn, a0, b0, na, nbw)


@nb.njit(cache=True, inline="always")
def read_in(m: int, v: int, V: int, va: np.ndarray, vb: np.ndarray, sdone: np.ndarray,
            sval: np.ndarray, dd: np.ndarray, dn: np.ndarray, a0: int, b0: int, na: int,
            nbw: int) -> float:
    """:func:`read_settled` with the tables ``hs[11]``, ``hs[12]``, ``hs[9]``, ``hs[10]``
    (``va``, ``vb``, ``sdone``, ``sval``) read once by the caller: in a hot loop each read
    of a tuple's array costs a reference count."""
    if v < V:
        a = va[v] - a0
        b = vb[v] - b0
        if 0 <= a < na and 0 <= b < nbw:
            j = (b + 1) * (na + 2) + a + 1
            if dn[j]:
                return dd[j]
    elif sdone[m, v - V]:
        return sval[m, v - V]
    return -1.0


@nb.njit(cache=True, inline="always")
def goal_views(m: int, hs: tuple) -> tuple[np.ndarray, np.ndarray, int, int, int, int]:
    """Goal m's window tables and bounds as :func:`read_in` takes them: ``(dd, dn, a0,
    b0, na, nbw)``. Read again after :func:`hval` on a miss: it may grow them."""
    w = hs[0]
    return hs[2][m], hs[3][m], w[m, 0], w[m, 1], w[m, 2], w[m, 3]


@nb.njit(cache=True, inline="always")
def hval_fast(m: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    """:func:`hval`, compiled into its caller: a settled or memoised value read in place."""
    return hval_in(m, v, gr, V, gv0, hs, hs[0], hs[11], hs[12], hs[9], hs[10])


@nb.njit(cache=True, inline="always")
def hval_in(m: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple, win: np.ndarray,
            va: np.ndarray, vb: np.ndarray, sdone: np.ndarray, sval: np.ndarray) -> float:
    """:func:`hval_fast` with the tables ``hs[0]``, ``hs[11]``, ``hs[12]``, ``hs[9]``,
    ``hs[10]`` read once by the caller (see :func:`read_in`)."""
    h = read_in(m, v, V, va, vb, sdone, sval, hs[2][m], hs[3][m], win[m, 0], win[m, 1],
                win[m, 2], win[m, 3])
    return h if h >= 0.0 else hval(m, v, gr, V, gv0, hs)


@nb.njit(cache=True)
def hval_below(pm: np.ndarray, pv: np.ndarray, bound: float, gr: tuple, V: int, gv0: int,
               hs: tuple, room: float = 0.0) -> np.ndarray:
    """For pairs (goal ``pm[k]``, special vertex ``pv[k]``): the exact distance when it is
    below ``bound``, else inf (each goal's search is expanded to ``bound`` once, a window
    opened for it reaching ``room``, :func:`expand_to`; pairs are best grouped by goal).
    A pair's value is its best link: the link's length plus its lattice node's settled
    value (``+ EPS`` for a direct link to the goal)."""
    coords, _, _, xptr, xidx = gr
    va, vb, sdone, sval = hs[11], hs[12], hs[9], hs[10]
    out = np.empty(pm.shape[0])
    last = -1
    dd, dn = hs[2][0], hs[3][0]
    a0 = b0 = na = nbw = 0
    for k in range(pm.shape[0]):
        m = pm[k]
        if m != last:
            expand_to(m, bound, gr[1], gr[2], hs, room)
            last = m
            dd, dn, a0, b0, na, nbw = goal_views(m, hs)
        v = pv[k]
        best = np.inf
        if v == gv0 + m:
            best = 0.0
        else:
            for e in range(xptr[v], xptr[v + 1]):
                n = xidx[e]
                dx = coords[v, 0] - coords[n, 0]
                dy = coords[v, 1] - coords[n, 1]
                ln = math.sqrt(dx * dx + dy * dy)
                if n < V:
                    h = read_in(m, n, V, va, vb, sdone, sval, dd, dn, a0, b0, na, nbw)
                    c = ln + (h if h >= 0.0 else np.inf)
                elif n == gv0 + m:
                    c = ln + EPS
                else:
                    continue
                if c < best:
                    best = c
        out[k] = best if best < bound else np.inf
    return out
