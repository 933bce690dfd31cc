"""Any-angle shortcuts of a synchronised fleet plan, before the retiming.

Gspi's paths run on the lattice: eight directions, so a path is up to 8 % longer than
the straight line even where nothing is in the way. :func:`shortcut_rows` replaces, for
the robots that arrive last, runs of rows ``s .. e`` of a robot's path by the straight
segment from its position at row ``s`` to its position at row ``e``: each move of the run
keeps its row and becomes the matching piece of the segment, in proportion to its length
(a wait stays a wait, and every move gets no longer, so no row lasts longer).

Kept: the rows (every robot's position at each synchronised row), and the rule every
row of the plan obeys, which the retiming (:mod:`lamp.mrmp.retime`) relies on. A run is
replaced only when

- the segment keeps an exact clearance of at least ``need`` (the space's threshold
  ``r + margin``) from the obstacles and the border, so every piece of it does;
- each new move, in its row, passes :func:`lamp.mrmp.gspi_kernels.conflict` against the
  motion of every other robot in that row (the same exact rule as Gspi's steps and the
  repair: the distance never falls below ``min(2r, distance at the row's start)``, two
  robots ending on goals excepted as there), with the other robots' rows as they are by
  then (earlier shortcuts included).

The rows before ``s`` and from ``e`` on are untouched, so every row stays checked. The
robots are taken in order of their arrival estimate (moves' lengths and ``wait_cost`` per
wait, :func:`lamp.mrmp.repair._cost`), largest first, those within ``frac`` of the
largest; along each robot's path greedily from its start: the farthest ``e`` (at most
``window`` rows on) whose run can be replaced, then on from ``e``. Deterministic.

Other robots are found through the repair's spatial hash of the positions at each row
(:mod:`lamp.mrmp.repair_hash`: cells wider than the distance within which two robots can
conflict in one row; a new move is never longer than the move it replaces, and a new
position lies between two old ones, so the cells and the table stay valid).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.gspi_kernels import conflict
from lamp.mrmp.obstacle_grid import grid_clear_segments
from lamp.mrmp.repair_hash import cell, hash_rows, set_key, span

__all__ = ["SHORTCUT_FRAC", "SHORTCUT_WINDOW", "shortcut_rows"]

#: Robots whose arrival estimate is at least this share of the largest are shortcut.
SHORTCUT_FRAC = 0.7
#: The most rows one straight segment replaces.
SHORTCUT_WINDOW = 16


@nb.njit(cache=True)
def _clear_of_robots(i: int, s: int, Q: np.ndarray, goal_end: bool, P: np.ndarray,
                     isgoal: np.ndarray, hh: tuple, x0: float, y0: float, cs: float, ny: int,
                     two_r: float) -> bool:
    """Whether robot i moving through ``Q`` (its positions at rows s, s+1, ...) keeps
    clear of every other robot's motion in each of those rows; ``goal_end``: its last
    position is its goal."""
    so = hh[1]
    n = Q.shape[0] - 1
    for m in range(n):
        t = s + m
        ax, ay = Q[m, 0], Q[m, 1]
        bx, by = Q[m + 1, 0], Q[m + 1, 1]
        kc = cell(ax, ay, x0, y0, cs, ny)
        at_goal = goal_end and m == n - 1
        for dx in range(-1, 2):
            p, q = span(t, kc + dx * ny - 1, hh)
            for e in range(p, q):
                k = so[t, e]
                if k == i:
                    continue
                if conflict(ax, ay, bx, by, P[t, k, 0], P[t, k, 1], P[t + 1, k, 0],
                            P[t + 1, k, 1], two_r, at_goal and isgoal[t + 1, k]):
                    return False
    return True


@nb.njit(cache=True)
def _run_positions(P: np.ndarray, i: int, s: int, e: int, cum: np.ndarray,
                   Q: np.ndarray) -> float:
    """Robot i's positions at rows s..e on the straight segment between its positions at
    rows s and e, each move in proportion to its length, into ``Q[:e - s + 1]``; returns
    the length saved."""
    ax, ay = P[s, i, 0], P[s, i, 1]
    bx, by = P[e, i, 0], P[e, i, 1]
    total = cum[e] - cum[s]
    d = math.hypot(bx - ax, by - ay)
    for m in range(e - s + 1):
        f = min(cum[s + m] - cum[s], d) / d if d > 0.0 else 1.0
        if f >= 1.0:
            Q[m, 0] = bx
            Q[m, 1] = by
        else:
            Q[m, 0] = ax + f * (bx - ax)
            Q[m, 1] = ay + f * (by - ay)
    return total - d


@nb.njit(cache=True)
def _one_robot(i: int, P: np.ndarray, isgoal: np.ndarray, hh: tuple, x0: float, y0: float,
               cs: float, ny: int, two_r: float, window: int, ob: tuple) -> int:
    """Shortcut robot i's path greedily from its start (module docstring); returns the
    runs replaced."""
    K1 = P.shape[0]
    a = K1 - 1
    while a > 0 and P[a - 1, i, 0] == P[K1 - 1, i, 0] and P[a - 1, i, 1] == P[K1 - 1, i, 1]:
        a -= 1
    cum = np.zeros(K1)
    for t in range(1, K1):
        cum[t] = cum[t - 1] + math.hypot(P[t, i, 0] - P[t - 1, i, 0],
                                         P[t, i, 1] - P[t - 1, i, 1])
    Q = np.empty((window + 1, 2))
    sa = np.empty((window, 2))
    sb = np.empty((window, 2))
    cand = np.empty(window, np.int64)
    need, circles, verts, vptr, W, H, gptr, gidx, box, gnx, gny, gcell = ob
    needs = np.full(window, need[0])
    done = 0
    s = 0
    while s < a - 1:
        nxt = s + 1
        nc = 0  # the ends e that would shorten the path, farthest first
        for e in range(min(a, s + window), s + 1, -1):
            d = math.hypot(P[e, i, 0] - P[s, i, 0], P[e, i, 1] - P[s, i, 1])
            if cum[e] - cum[s] <= 0.0 or cum[e] - cum[s] - d <= 1e-9:
                continue
            sa[nc, 0], sa[nc, 1] = P[s, i, 0], P[s, i, 1]
            sb[nc, 0], sb[nc, 1] = P[e, i, 0], P[e, i, 1]
            cand[nc] = e
            nc += 1
        clear = grid_clear_segments(sa[:nc], sb[:nc], needs[:nc], circles, verts, vptr, W, H,
                                    gptr, gidx, box, gnx, gny, gcell)
        for c in range(nc):
            e = cand[c]
            if not clear[c]:
                continue
            _run_positions(P, i, s, e, cum, Q)
            if not _clear_of_robots(i, s, Q[: e - s + 1], isgoal[e, i], P, isgoal, hh, x0,
                                    y0, cs, ny, two_r):
                continue
            for m in range(1, e - s):
                t = s + m
                P[t, i, 0] = Q[m, 0]
                P[t, i, 1] = Q[m, 1]
                isgoal[t, i] = False
                set_key(t, i, cell(Q[m, 0], Q[m, 1], x0, y0, cs, ny), hh)
            for t in range(s + 1, K1):
                cum[t] = cum[t - 1] + math.hypot(P[t, i, 0] - P[t - 1, i, 0],
                                                 P[t, i, 1] - P[t - 1, i, 1])
            done += 1
            nxt = e
            break
        s = nxt
    return done


@nb.njit(cache=True)
def _shortcut(P: np.ndarray, isgoal: np.ndarray, order: np.ndarray, two_r: float,
              max_move: float, window: int, ob: tuple) -> int:
    """Shortcut the robots of ``order`` in turn, in place; returns the runs replaced."""
    K1, N, _ = P.shape
    cs = two_r + 2.0 * max_move + 1e-6
    x0 = P[:, :, 0].min()
    y0 = P[:, :, 1].min()
    xmax = P[:, :, 0].max()
    ymax = P[:, :, 1].max()
    hh, ny = hash_rows(np.ascontiguousarray(P[:, :, 0]), np.ascontiguousarray(P[:, :, 1]),
                       x0, y0, xmax, ymax, cs, True)
    done = 0
    for q in range(order.shape[0]):
        done += _one_robot(order[q], P, isgoal, hh, x0, y0, cs, ny, two_r, window, ob)
    return done


def shortcut_rows(P: np.ndarray, isgoal: np.ndarray, cost: np.ndarray, two_r: float,
                  max_move: float, geometry, workspace: tuple[float, float], need: float,
                  frac: float = SHORTCUT_FRAC, window: int = SHORTCUT_WINDOW
                  ) -> tuple[np.ndarray, int]:
    """The synchronised rows ``P`` ((K+1, N, 2) positions) with the shortcuts of the
    module docstring; ``isgoal`` ((K+1, N)): whether each position is a goal (two robots
    ending on goals may end closer, as in Gspi's rule); ``cost``: each robot's arrival
    estimate; ``max_move``: the longest move of the plan at most. Returns the new rows
    (all-still rows dropped) and the number of runs replaced."""
    from lamp.mrmp.obstacle_grid import get_grid

    P = np.array(P, dtype=np.float64, order="C")
    isgoal = np.array(isgoal, dtype=np.bool_, order="C")
    if P.shape[0] < 3 or P.shape[1] == 0:
        return P, 0
    order = np.argsort(-np.asarray(cost), kind="stable")
    order = order[np.asarray(cost)[order] >= frac * float(np.max(cost))]
    g = get_grid(geometry)
    W, H = workspace
    ob = (np.full(1, float(need)), geometry.circles, geometry.verts, geometry.ptr, float(W),
          float(H), g.ptr, g.idx, g.box, g.nx, g.ny, g.cell)
    done = _shortcut(P, isgoal, order.astype(np.int64), float(two_r), float(max_move),
                     int(window), ob)
    moved = np.any(np.any(P[1:] != P[:-1], axis=2), axis=1)
    return np.ascontiguousarray(P[np.concatenate([[True], moved])]), done
