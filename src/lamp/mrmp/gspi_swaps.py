"""Gspi's goal swaps and TSWAP's deadlock rule (compiled; called by
:func:`lamp.mrmp.gspi_kernels.run_steps` before each PIBT step)."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.borrow import borrowed
from lamp.mrmp.goal_distances import hval
from lamp.mrmp.heuristic_reads import hval_in

__all__ = ["STUCK_STEPS", "break_deadlocks", "swap_goals"]

#: Steps a robot may go without progress towards its goal before it trades goals with a
#: neighbour that blocks it (``break_deadlocks``).
STUCK_STEPS = 10


@nb.njit(cache=True, inline="always")
def _h_now(i: int, g: int, cur: np.ndarray, gr: tuple, V: int, gv0: int, hs: tuple,
           hcur: np.ndarray, hgoal: np.ndarray, tabs: tuple) -> float:
    """Robot i's value to its goal g from where it is (0 without a goal), kept;
    ``tabs``: ``hs[0], hs[11], hs[12], hs[9], hs[10]`` (``heuristic_reads.hval_in``)."""
    if g < 0:
        return 0.0
    if hgoal[i] != g:
        hcur[i] = hval_in(g, cur[i], gr, V, gv0, hs, tabs[0], tabs[1], tabs[2], tabs[3],
                          tabs[4])
        hgoal[i] = g
    return hcur[i]


@nb.njit(cache=True)
def swap_goals(gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
                prio: np.ndarray, sptr: np.ndarray, sidx: np.ndarray, cool: np.ndarray,
                fleet: bool, hcur: np.ndarray, hgoal: np.ndarray) -> int:
    """Pairwise goal swaps that lower the summed heuristic (priorities travel along), over
    the pairs (i, j > i) of the neighbour lists, in index order; robots with ``cool > 0``
    (just traded goals to break a deadlock) take no part. ``hcur[i]``: robot i's value
    to goal ``hgoal[i]`` from where it is, when that is its goal (read once, kept here).

    In a fleet, TSWAP's rule: a pair swaps only when one of them rests on its goal (or has
    none), and only when the swap lowers the longer of their two distances, or keeps it
    and lowers the sum: swaps never lengthen the longest way left. The arguments are
    borrowed (:mod:`lamp.mrmp.borrow`): ``_h_now`` binds them once per pair."""
    gr, hs, cur, goal, prio, sptr, sidx, cool, hcur, hgoal = borrowed(
        (gr, hs, cur, goal, prio, sptr, sidx, cool, hcur, hgoal))
    coords = gr[0]
    win, va, vb, sdone, sval = hs[0], hs[11], hs[12], hs[9], hs[10]
    tabs = (win, va, vb, sdone, sval)
    N = cur.shape[0]
    nswap = 0
    for i in range(N):
        for q in range(sptr[i], sptr[i + 1]):
            j = sidx[q]
            if j <= i or cool[i] > 0 or cool[j] > 0:
                continue
            gi = goal[i]
            gj = goal[j]
            if gi < 0 and gj < 0:
                continue
            if fleet and gi >= 0 and gj >= 0 and cur[i] != gv0 + gi and cur[j] != gv0 + gj:
                continue
            hi = _h_now(i, gi, cur, gr, V, gv0, hs, hcur, hgoal, tabs)
            hj = _h_now(j, gj, cur, gr, V, gv0, hs, hcur, hgoal, tabs)
            now = hi + hj
            now_max = max(hi, hj)
            # straight-line lower bound of the swapped sum: far pairs are skipped without
            # expanding either goal's search to the other robot (the same decisions)
            la = 0.0
            lb = 0.0
            if gi >= 0:
                la = math.hypot(coords[cur[j], 0] - coords[gv0 + gi, 0],
                                coords[cur[j], 1] - coords[gv0 + gi, 1])
            if gj >= 0:
                lb = math.hypot(coords[cur[i], 0] - coords[gv0 + gj, 0],
                                coords[cur[i], 1] - coords[gv0 + gj, 1])
            if la + lb >= now - 1e-9 and (not fleet or max(la, lb) >= now_max - 1e-9):
                continue
            if fleet and max(la, lb) > now_max + 1e-9:
                continue
            sa = hval_in(gi, cur[j], gr, V, gv0, hs, win, va, vb, sdone,
                         sval) if gi >= 0 else 0.0
            sb = hval_in(gj, cur[i], gr, V, gv0, hs, win, va, vb, sdone,
                         sval) if gj >= 0 else 0.0
            sw = sa + sb
            if fleet:
                sw_max = max(sa, sb)
                better = sw_max < now_max - 1e-9 or (sw_max <= now_max + 1e-9
                                                     and sw < now - 1e-9)
            else:
                better = sw < now - 1e-9
            if better:
                goal[i] = gj
                goal[j] = gi
                hcur[i], hgoal[i], hcur[j], hgoal[j] = sb, gj, sa, gi
                p = prio[i]
                prio[i] = prio[j]
                prio[j] = p
                nswap += 1
    return nswap


@nb.njit(cache=True)
def break_deadlocks(gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray,
                     goal: np.ndarray, prio: np.ndarray, nptr: np.ndarray, nidx: np.ndarray,
                     stuck: np.ndarray, besth: np.ndarray, near: float) -> int:
    """TSWAP's deadlock rule in continuous space: a robot that has made no progress
    towards its goal for :data:`STUCK_STEPS` steps trades goals (and priorities)
    with the first robot within reach, in index order, that is stuck too, or that rests
    on its goal nearer to the stuck robot's goal (it stands in the way); "within reach":
    closer than ``near``, so that the two can block each other. The summed
    heuristic may grow; what it buys is that neither blocks the other any more (two
    robots each blocking the other's last move are otherwise stuck for good). The
    arguments are borrowed (:mod:`lamp.mrmp.borrow`)."""
    gr, hs, cur, goal, prio, nptr, nidx, stuck, besth = borrowed(
        (gr, hs, cur, goal, prio, nptr, nidx, stuck, besth))
    coords = gr[0]
    N = cur.shape[0]
    n = 0
    for i in range(N):
        gi = goal[i]
        if stuck[0, i] < STUCK_STEPS or gi < 0:
            continue
        hi = hval(gi, cur[i], gr, V, gv0, hs)
        xi = coords[cur[i], 0]
        yi = coords[cur[i], 1]
        for q in range(nptr[i], nptr[i + 1]):
            j = nidx[q]
            gj = goal[j]
            if gj < 0 or math.hypot(coords[cur[j], 0] - xi, coords[cur[j], 1] - yi) > near:
                continue
            resting = cur[j] == gv0 + gj
            if not (stuck[0, j] >= STUCK_STEPS
                    or (resting and hval(gi, cur[j], gr, V, gv0, hs) < hi - 1e-9)):
                continue
            goal[i] = gj
            goal[j] = gi
            p = prio[i]
            prio[i] = prio[j]
            prio[j] = p
            stuck[0, i] = 0
            stuck[0, j] = 0
            # no improving swap undoes the trade before either has moved on
            stuck[1, i] = 2 * STUCK_STEPS
            stuck[1, j] = 2 * STUCK_STEPS
            besth[i] = np.inf
            besth[j] = np.inf
            n += 1
            break
    return n
