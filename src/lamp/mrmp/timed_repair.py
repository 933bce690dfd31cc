"""Repair of a retimed fleet plan: the robots that arrive last are planned again in time.

After the retiming (:mod:`lamp.mrmp.retime`) every robot moves at its own speed, but it
keeps the order in which the synchronised plan let two robots pass the same place: a robot
that waited there for another waits in the retimed plan too, however early it could have
passed. At 800 robots on a 9.6 m map such waits and slow moves made up 0.1-0.5 m of the
last robot's arrival. :func:`timed_repair` plans the robot that arrives last again,
against every other robot's retimed motion as it is, in continuous time, and keeps the
new way when it arrives earlier; then the next last robot, until the last one cannot
arrive earlier or the work bound is spent.

When the last robot has no earlier way as the others move, the others in its way are
planned again with it (:func:`_one_round`): its earliest way as if the others were only
at their last positions from their arrivals on (then, failing that, as if there were no
other robot) names the robots whose motion that way would cross (at most
:data:`TIMED_GROUP`); their motions are set aside, the last robot is planned again, then
each of them, latest first, every one to arrive before the same target, against every
motion kept and every new way; all are kept or none. When one of them finds no way, all
are planned again with it first (prioritised planning's restart on failure: a way found
early for the last robot may cross where a member must pass; up to
:data:`TIMED_RESTARTS` times). Failing that, the last robot
exchanges goals with one of them (the :data:`TIMED_EXCHANGES` latest), both planned
again the same way (the goals are interchangeable, so the exchange is returned with the
rows); then with the holders of the goals near its start whose own start lies near its
goal (:func:`_near_holders`: the :data:`TIMED_EXCHANGES` whose longer straight line is
shortest, below the target); when it has no earlier way even with no other robot
about, only these exchanges are tried. Robots tied with the last are tried in turn
before the loop ends. Without groups (up to :data:`TIMED_BUDGET_ROBOTS` robots), over safe
intervals, a last robot with no earlier way whose lattice distance is near the target is
searched again with the lower-bound heuristic, as in a group round.

Search (:mod:`lamp.mrmp.timed_search`): A* over (vertex, time) of the plan's graph
(lattice nodes, the robot's own start and goal vertices' links, other goals' vertices;
never another robot's start vertex) and knight moves between lattice nodes whose segment
keeps the space's clearance, time in whole quanta ``q`` (the retiming's). In fleets of
more than :data:`TIMED_SIPP_FROM` robots the searches against the others' motion go over
safe intervals instead (:mod:`lamp.mrmp.timed_sipp`: the same graph, moves and checks,
waits of any length; a state per vertex and interval rather than per vertex and time);
the searches as if the others were only at their last positions, or absent, stay over
(vertex, time), where a vertex is kept at its earliest time only.

Why the plan stays valid: the graph's edges are the obstacle-checked lattice edges and
links; every move and wait of the new way is checked against the motion of every other
robot in each row it overlaps, cut at the rows' times (both linear there, so the check is
exact), with Gspi's rule (:func:`lamp.mrmp.gspi_kernels.conflict`: the distance never
falls below ``min(2r, distance at the piece's start)``, two robots ending on goals
excepted), and so is the stay on the goal to the end. The other robots' rows are
unchanged but for the robots planned again (whose old motions are replaced, each new way
checked against all the others); new rows are only inserted at the new ways' times (the
other robots move linearly between rows, so their positions there are exact), and every
robot still moves at most ``max_spacing`` between rows. Deterministic: bounded by a count of states.

Other robots are found through a spatial hash of the rows (:mod:`lamp.mrmp.repair_hash`),
cells wider than ``2r`` plus the longest distance two robots move within a piece.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from lamp.mrmp.goal_distances import hval
from lamp.mrmp.neighbours import doubled
from lamp.mrmp.repair_hash import hash_rows
from lamp.mrmp.safe_intervals import segment_index
from lamp.mrmp.timed_checks import arrivals, motion_hits, with_way
from lamp.mrmp.timed_search import TIGHT_FROM, timed_search
from lamp.mrmp.timed_sipp import sipp_search

__all__ = ["TIMED_BUDGET", "TIMED_BUDGET_MAX", "TIMED_BUDGET_ROBOTS", "TIMED_ENTRIES",
           "TIMED_EXCHANGES", "TIMED_GROUP", "TIMED_RESTARTS", "TIMED_ROUNDS",
           "TIMED_SIPP_FROM", "timed_budget", "timed_repair"]

#: States all the searches of one call may expand together (the work bound), for up to
#: :data:`TIMED_BUDGET_ROBOTS` robots; beyond, it grows with the square of the robots
#: (as the steps' and the grid solvers' times do), up to :data:`TIMED_BUDGET_MAX`.
TIMED_BUDGET = 5000
#: See :data:`TIMED_BUDGET`.
TIMED_BUDGET_ROBOTS = 400
#: See :data:`TIMED_BUDGET`.
TIMED_BUDGET_MAX = 40_000
#: The most rounds of one call (a round plans the last robot again, alone or with others).
TIMED_ROUNDS = 48
#: Plans of more rows times robots are left as they are: the rows' hash and the
#: searches' checks grow with them (a 1,600-robot plan on ``den520d``, 1.4-1.9 million,
#: took 0.15-0.35 s for a few hundredths of a metre).
TIMED_ENTRIES = 1_000_000
#: The most robots in the way of the last one planned again with it (0: none, and no
#: exchanges nor lower-bound searches either: the default up to
#: :data:`TIMED_BUDGET_ROBOTS` robots, where the plain search alone spends the budget
#: in less time for as short plans, measured over 12 instances of 400 robots).
TIMED_GROUP = 8
#: Fleets of more robots than this search over safe intervals
#: (:func:`lamp.mrmp.timed_sipp.sipp_search`) where the others move; smaller ones over
#: (vertex, time) (:func:`lamp.mrmp.timed_search.timed_search`).
TIMED_SIPP_FROM = 100
#: Restarts of a group of robots planned again together (:func:`_plan_members`): each
#: time one of them finds no way, all are planned again with it first (0: none).
TIMED_RESTARTS = 4
#: Goal exchanges tried for the last robot with the robots in its way, and then with
#: the holders of goals near its start (each; 0: none).
TIMED_EXCHANGES = 8


@nb.njit(cache=True)
def _plain(segs: tuple, i: int, m: int, gr: tuple, V: int, gv0: int, hs: tuple,
           X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float, y0: float,
           cs: float, ny: int, two_r: float, ends_goal: np.ndarray, q: float, target: int,
           budget: int, ob: tuple, ways: tuple, arr: np.ndarray, tight: bool
           ) -> tuple[np.ndarray, np.ndarray, int]:
    """Robot i's way to goal m against the others' motion: over safe intervals with the
    rows' segments ``segs`` (:func:`lamp.mrmp.safe_intervals.segment_index`), or over
    (vertex, time) when ``segs`` has none; its vertices, their times and the states
    expanded."""
    if segs[0].shape[0] > 0:
        pv, pt, work, _ = sipp_search(i, m, gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs, ny,
                                      two_r, ends_goal, q, target, budget, ob, ways, segs,
                                      tight)
        return pv, pt, work
    return timed_search(i, m, gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs, ny, two_r,
                        ends_goal, q, target, budget, ob, ways, arr, 0, tight)


@nb.njit(cache=True)
def _add_way(i: int, pv: np.ndarray, pt: np.ndarray, coords: np.ndarray, q: float,
             WX: np.ndarray, WY: np.ndarray, WT: np.ndarray, wptr: np.ndarray,
             wrob: np.ndarray, box: np.ndarray, nw: int
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Robot i's new way (vertices ``pv`` at ``pt`` quanta) written as way ``nw``, its
    earlier ways marked replaced; returns ``WX, WY, WT`` (grown when full)."""
    for u in range(nw):
        if wrob[u] == i:
            wrob[u] = -1
    p0 = wptr[nw]
    while p0 + pv.shape[0] > WX.shape[0]:
        WX, WY, WT = doubled(WX, p0), doubled(WY, p0), doubled(WT, p0)
    for k in range(pv.shape[0]):
        WX[p0 + k], WY[p0 + k] = coords[pv[k], 0], coords[pv[k], 1]
        WT[p0 + k] = pt[k] * q
    p1 = p0 + pv.shape[0]
    wptr[nw + 1] = p1
    wrob[nw] = i
    box[nw, 0], box[nw, 1] = WX[p0:p1].min(), WX[p0:p1].max()
    box[nw, 2], box[nw, 3] = WY[p0:p1].min(), WY[p0:p1].max()
    return WX, WY, WT


@nb.njit(cache=True)
def _in_the_way(i: int, pv: np.ndarray, pt: np.ndarray, coords: np.ndarray, q: float,
                X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float,
                y0: float, cs: float, ny: int, two_r: float, ends_goal: np.ndarray,
                ways: tuple) -> np.ndarray:
    """The robots whose motion robot i's way (vertices ``pv`` at ``pt`` quanta, then
    its stay on the last to the end) would not keep clear of."""
    hit = np.zeros(X.shape[1], np.bool_)
    n = pv.shape[0]
    for k in range(n - 1):
        a, b = pv[k], pv[k + 1]
        motion_hits(i, coords[a, 0], coords[a, 1], coords[b, 0], coords[b, 1], pt[k] * q,
                    pt[k + 1] * q, k == n - 2, X, Y, tt, hh, x0, y0, cs, ny, two_r,
                    ends_goal, ways, hit)
    g = pv[n - 1]
    t_end = pt[n - 1] * q
    motion_hits(i, coords[g, 0], coords[g, 1], coords[g, 0], coords[g, 1], t_end,
                max(t_end, tt[tt.shape[0] - 1]) + 1.0, True, X, Y, tt, hh, x0, y0, cs, ny,
                two_r, ends_goal, ways, hit)
    hit[i] = False
    return np.nonzero(hit)[0]


@nb.njit(cache=True)
def _plan_members(members: np.ndarray, pv: np.ndarray, pt: np.ndarray, target: int,
                  gr: tuple, V: int, gv0: int, hs: tuple, goal: np.ndarray, X: np.ndarray,
                  Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
                  ny: int, two_r: float, q: float, budget: int, ob: tuple, arr: np.ndarray,
                  state: tuple, segs: tuple, restarts: int) -> tuple:
    """Plan the ``members`` again in turn, each to arrive before ``target``, the others'
    old motions ignored meanwhile (the first's way ``pv, pt`` when given); all or none
    are kept. When one of them finds no way, they are planned again with it first (the
    others in their order), up to ``restarts`` times (:data:`TIMED_RESTARTS`), and not
    when it was first in a try already (it met only the motions kept then; a pair is
    thus tried in both orders, no more). ``state = (rep, WX, WY, WT, wptr, wrob, box,
    nw)``; returns it updated, with whether they were kept and the states expanded."""
    order = members.copy()
    first = np.zeros(goal.shape[0], np.bool_)  # robots planned first in a try
    work = 0
    for attempt in range(restarts + 1):
        first[order[0]] = True
        state, j, w = _plan_order(order, pv if attempt == 0 else pv[:0],
                                  pt if attempt == 0 else pt[:0], target, gr, V, gv0, hs,
                                  goal, X, Y, tt, hh, x0, y0, cs, ny, two_r, q, budget - work,
                                  ob, arr, state, segs)
        work += w
        if j < 0:
            return state, True, work
        if first[j] or work >= budget:
            break
        k = 0
        while order[k] != j:
            k += 1
        order[1: k + 1] = order[:k].copy()
        order[0] = j
    return state, False, work


@nb.njit(cache=True)
def _plan_order(members: np.ndarray, pv: np.ndarray, pt: np.ndarray, target: int,
                gr: tuple, V: int, gv0: int, hs: tuple, goal: np.ndarray, X: np.ndarray,
                Y: np.ndarray, tt: np.ndarray, hh: tuple, x0: float, y0: float, cs: float,
                ny: int, two_r: float, q: float, budget: int, ob: tuple, arr: np.ndarray,
                state: tuple, segs: tuple) -> tuple:
    """One try of :func:`_plan_members` in the order ``members``: the state (unchanged
    unless all were planned), the member that found no way (-1: none) and the states
    expanded."""
    rep, WX, WY, WT, wptr, wrob, box, nw = state
    ends_goal = goal >= 0
    nw0, rep0, wrob0, arr0 = nw, rep.copy(), wrob[:nw].copy(), arr.copy()
    for j in members:
        rep[j] = True
        for u in range(nw):
            if wrob[u] == j:
                wrob[u] = -1
    work = 0
    for j in members:
        if pv.shape[0] == 0:
            ways = (rep, WX, WY, WT, wptr[: nw + 1], wrob[:nw], box[:nw])
            pv, pt, w = _plain(segs, j, goal[j], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs,
                               ny, two_r, ends_goal, q, target, budget - work, ob, ways, arr,
                               members.shape[0] > 1 and hval(goal[j], V + j, gr, V, gv0, hs)
                               >= TIGHT_FROM * target * q)
            work += w
            if pv.shape[0] == 0:
                rep[:] = rep0
                wrob[:nw0] = wrob0
                arr[:] = arr0
                return (rep, WX, WY, WT, wptr, wrob, box, nw0), j, work
        WX, WY, WT = _add_way(j, pv, pt, gr[0], q, WX, WY, WT, wptr, wrob, box, nw)
        arr[j] = WT[wptr[nw + 1] - 1]
        nw += 1
        pv = pv[:0]
    return (rep, WX, WY, WT, wptr, wrob, box, nw), -1, work


@nb.njit(cache=True)
def _one_round(i: int, target: int, gr: tuple, V: int, gv0: int, hs: tuple,
               goal: np.ndarray, X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple,
               x0: float, y0: float, cs: float, ny: int, two_r: float, q: float,
               budget: int, ob: tuple, arr: np.ndarray, state: tuple, group: int,
               exchanges: int, segs: tuple, restarts: int) -> tuple:
    """Robot i planned again to arrive before ``target`` (:func:`_rounds`): alone, then
    alone with the lower-bound heuristic where its lattice distance is near the target
    (with groups, or over safe intervals), else (``group > 0``) with the robots in its way, or
    exchanging goals with one of them, then with a holder of a goal near its start
    (:func:`_near_holders`); only the last when it has no such way even with no other
    robot about; ``segs``: :func:`_plain`'s. Returns the state, whether it was
    planned, and the states expanded."""
    ends_goal = goal >= 0
    rep, WX, WY, WT, wptr, wrob, box, nw = state
    ways = (rep, WX, WY, WT, wptr[: nw + 1], wrob[:nw], box[:nw])
    pv, pt, work = _plain(segs, i, goal[i], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs, ny,
                          two_r, ends_goal, q, target, budget, ob, ways, arr, False)
    fv, ft = pv, pt
    if pv.shape[0] == 0 and group > 0:
        # no earlier way even with nobody about (fv empty): neither alone nor in a group,
        # only with another goal
        fv, ft, w = timed_search(i, goal[i], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs, ny,
                                 two_r, ends_goal, q, target, budget - work, ob, ways, arr, 2,
                                 True)
        work += w
        # the plain heuristic prunes at once the ways only knight moves make early enough
        if fv.shape[0] > 0 and hval(goal[i], V + i, gr, V, gv0, hs) >= \
                TIGHT_FROM * target * q:
            pv, pt, w = _plain(segs, i, goal[i], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs,
                               ny, two_r, ends_goal, q, target, budget - work, ob, ways, arr,
                               True)
            work += w
    elif pv.shape[0] == 0 and segs[0].shape[0] > 0 and \
            hval(goal[i], V + i, gr, V, gv0, hs) >= TIGHT_FROM * target * q:
        pv, pt, w = _plain(segs, i, goal[i], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs, ny,
                           two_r, ends_goal, q, target, budget - work, ob, ways, arr, True)
        work += w
    me = np.full(1, i, np.int64)
    tried = np.zeros(goal.shape[0], np.bool_)  # exchange partners tried
    if pv.shape[0] > 0:
        state, ok, w = _plan_members(me, pv, pt, target, gr, V, gv0, hs, goal, X, Y, tt, hh,
                                     x0, y0, cs, ny, two_r, q, budget - work, ob, arr, state,
                                     segs, restarts)
        return state, ok, work + w
    for alone in range(1, 3 if group > 0 and fv.shape[0] > 0 else 1):
        if work >= budget:
            break
        pv, pt = fv, ft
        if alone == 1:
            pv, pt, w = timed_search(i, goal[i], gr, V, gv0, hs, X, Y, tt, hh, x0, y0, cs,
                                     ny, two_r, ends_goal, q, target, budget - work, ob, ways,
                                     arr, 1, True)
            work += w
        if pv.shape[0] == 0:
            continue
        others = _in_the_way(i, pv, pt, gr[0], q, X, Y, tt, hh, x0, y0, cs, ny, two_r,
                             ends_goal, ways)
        if others.shape[0] == 0 or (goal[others] < 0).any():
            continue
        others = others[np.argsort(-arr[others], kind="mergesort")]
        if others.shape[0] <= group:
            state, ok, w = _plan_members(np.concatenate((me, others)), pv[:0], pt[:0], target,
                                         gr, V, gv0, hs, goal, X, Y, tt, hh, x0, y0, cs, ny,
                                         two_r, q, budget - work, ob, arr, state, segs,
                                         restarts)
            work += w
            if ok:
                return state, True, work
        tried[others[:exchanges]] = True
        state, ok, w = _exchange(i, others[:exchanges], target, gr, V, gv0, hs, goal, X, Y,
                                 tt, hh, x0, y0, cs, ny, two_r, q, budget - work, ob, arr,
                                 state, segs, restarts)
        work += w
        if ok:
            return state, True, work
    if group > 0 and exchanges > 0 and work < budget:
        near = _near_holders(i, goal, gr[0], V, gv0, target * q, tried, exchanges)
        state, ok, w = _exchange(i, near, target, gr, V, gv0, hs, goal, X, Y, tt, hh, x0,
                                 y0, cs, ny, two_r, q, budget - work, ob, arr, state, segs,
                                 restarts)
        return state, ok, work + w
    return state, False, work


@nb.njit(cache=True)
def _exchange(i: int, js: np.ndarray, target: int, gr: tuple, V: int, gv0: int, hs: tuple,
              goal: np.ndarray, X: np.ndarray, Y: np.ndarray, tt: np.ndarray, hh: tuple,
              x0: float, y0: float, cs: float, ny: int, two_r: float, q: float, budget: int,
              ob: tuple, arr: np.ndarray, state: tuple, segs: tuple, restarts: int
              ) -> tuple:
    """Robot i exchanges goals with each of ``js`` in turn, both planned again to arrive
    before ``target`` (:func:`_plan_members`), until one exchange is kept (``goal``
    updated in place). Returns the state, whether one was kept, and the states expanded."""
    work = 0
    for j in js:
        if work >= budget:
            break
        goal[i], goal[j] = goal[j], goal[i]
        state, ok, w = _plan_members(np.array([i, j]), np.zeros(0, np.int64),
                                     np.zeros(0, np.int64), target, gr, V, gv0, hs, goal, X,
                                     Y, tt, hh, x0, y0, cs, ny, two_r, q, budget - work, ob,
                                     arr, state, segs, restarts)
        work += w
        if ok:
            return state, True, work
        goal[i], goal[j] = goal[j], goal[i]
    return state, False, work


@nb.njit(cache=True)
def _near_holders(i: int, goal: np.ndarray, coords: np.ndarray, V: int, gv0: int,
                  limit: float, tried: np.ndarray, k: int) -> np.ndarray:
    """Up to ``k`` robots j for a goal exchange with robot i, not ``tried`` and holding a
    goal: those whose goal lies within ``limit`` of i's start and whose start lies within
    ``limit`` of i's goal (straight lines: a pair farther apart cannot arrive within
    ``limit`` at unit speed), the longer of the two lines shortest first, ties by index."""
    N = goal.shape[0]
    key = np.full(N, np.inf)
    sx, sy = coords[V + i, 0], coords[V + i, 1]
    gx, gy = coords[gv0 + goal[i], 0], coords[gv0 + goal[i], 1]
    for j in range(N):
        if j == i or goal[j] < 0 or tried[j]:
            continue
        a = math.hypot(coords[gv0 + goal[j], 0] - sx, coords[gv0 + goal[j], 1] - sy)
        b = math.hypot(coords[V + j, 0] - gx, coords[V + j, 1] - gy)
        if max(a, b) < limit:
            key[j] = max(a, b)
    order = np.argsort(key, kind="mergesort")[:k]
    return order[np.isfinite(key[order])]


@nb.njit(cache=True)
def _rounds(X: np.ndarray, Y: np.ndarray, tt: np.ndarray, gr: tuple, V: int, gv0: int,
            hs: tuple, goal: np.ndarray, two_r: float, q: float, cs: float,
            max_spacing: float, budget: int, rounds: int, ob: tuple, group: int,
            exchanges: int, sipp: bool, restarts: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int, int]:
    """The loop of :func:`timed_repair` on the rows ``X, Y`` (times ``tt``, metres):
    (rows, times, ways found, states expanded, rounds that planned several robots
    together); ``goal`` is updated in place by goal
    exchanges. The rows and their hash are kept while the new ways are found (each
    checked against the ways found before it), and the ways are written into the rows at
    the end. When the last robot has no earlier way alone, the robots in the way it
    would take without them (at most ``group``; first as if the others were only at
    their last positions from their arrivals on, then as if there were none) are
    planned again after it, each to arrive before the same target, all or none kept;
    else it exchanges goals with one of them (the ``exchanges`` latest), or with one of
    the ``exchanges`` holders of goals near its start, both planned again. Robots tied
    with the last are tried in turn before the loop ends. ``sipp``: search over safe
    intervals where the others move (:func:`_plain`); ``restarts``:
    :func:`_plan_members`'."""
    coords = gr[0]
    N = X.shape[1]
    x0, y0 = coords[:, 0].min(), coords[:, 1].min()
    x1, y1 = coords[:, 0].max(), coords[:, 1].max()
    arr = arrivals(X, Y, tt)
    hh, ny = hash_rows(X, Y, x0, y0, x1, y1, cs, True)
    # the rows' segments for the safe intervals; none: the searches over (vertex, time)
    segs = segment_index(X, Y, tt, two_r, x0, y0, x1, y1) if sipp else \
        segment_index(X[:0], Y[:0], tt[:0], two_r, x0, y0, x0, y0)
    cap = rounds * (group + 2)
    state = (np.zeros(N, np.bool_), np.empty(256), np.empty(256), np.empty(256),
             np.zeros(cap + 1, np.int64), np.full(cap, -1, np.int64), np.empty((cap, 4)), 0)
    skip = np.zeros(N, np.bool_)  # tried and failed at the present latest arrival
    work = 0
    groups = 0
    for _ in range(rounds):
        if work >= budget or tt.shape[0] < 2:
            break
        i = int(np.argmax(np.where(skip, -np.inf, arr)))
        if goal[i] < 0 or (skip.any() and arr[i] < arr.max() - 1e-9):
            break
        target = int(math.ceil(arr.max() / q - 1e-9))
        nw0 = state[7]
        state, ok, w = _one_round(i, target, gr, V, gv0, hs, goal, X, Y, tt, hh, x0, y0,
                                  cs, ny, two_r, q, budget - work, ob, arr, state, group,
                                  exchanges, segs, restarts)
        work += w
        if ok:
            groups += state[7] - nw0 > 1
            skip[:] = False
        else:
            skip[i] = True
    rep, WX, WY, WT, wptr, wrob, box, nw = state
    for u in range(nw):
        if wrob[u] >= 0:
            a, b = wptr[u], wptr[u + 1]
            X, Y, tt = with_way(X, Y, tt, wrob[u], WX[a:b], WY[a:b], WT[a:b], max_spacing)
    return X, Y, tt, nw, work, groups


def timed_budget(n_robots: int) -> int:
    """The default state budget of :func:`timed_repair` for a fleet of ``n_robots``
    (:data:`TIMED_BUDGET`)."""
    grow = max(1.0, n_robots / TIMED_BUDGET_ROBOTS) ** 2
    return int(min(TIMED_BUDGET_MAX, round(TIMED_BUDGET * grow)))


def timed_repair(rows: np.ndarray, times: np.ndarray, gr: tuple, V: int, gv0: int,
                 hs: tuple, goal: np.ndarray, two_r: float, quantum: float,
                 max_move: float, max_spacing: float, geometry, workspace: tuple[float, float],
                 need: float, budget: int | None = None, rounds: int = TIMED_ROUNDS,
                 group: int | None = None, exchanges: int = TIMED_EXCHANGES,
                 sipp: bool | None = None, restarts: int = TIMED_RESTARTS
                 ) -> tuple[np.ndarray, np.ndarray, int, int, int]:
    """The retimed ``rows`` ((N, R, 2), at ``times``, metres at unit speed) with their
    last robots planned again in time (module docstring) over the graph ``gr`` (goal
    distances ``hs``, robot i's start vertex ``V + i``, goal m's ``gv0 + m``);
    ``quantum``: the time step of the new ways (metres), ``max_move``: the graph's
    longest edge; ``geometry``, ``workspace``, ``need``: the obstacles, the workspace and
    the clearance a knight move keeps (the space's threshold); ``budget``, ``group``:
    None for the defaults by fleet size (:func:`timed_budget`, :data:`TIMED_GROUP`);
    ``sipp``: whether the searches against the others' motion go over safe intervals
    (None: for more than :data:`TIMED_SIPP_FROM` robots); ``restarts``: of a group planned
    again together (:data:`TIMED_RESTARTS`). Plans of more than
    :data:`TIMED_ENTRIES` rows times robots are returned as they are. Returns the rows,
    each robot's goal (``goal``, changed by the exchanges), the ways planned, the states
    expanded and the rounds that planned several robots together."""
    from lamp.mrmp.obstacle_grid import get_grid

    rows = np.asarray(rows, dtype=np.float64)
    goal = np.array(goal, dtype=np.int64)
    if budget is None:
        budget = timed_budget(rows.shape[0])
    if group is None:
        group = TIMED_GROUP if rows.shape[0] > TIMED_BUDGET_ROBOTS else 0
    if sipp is None:
        sipp = rows.shape[0] > TIMED_SIPP_FROM
    if rows.shape[0] < 2 or rows.shape[1] < 2 or rows.shape[0] * rows.shape[1] > TIMED_ENTRIES:
        return rows, goal, 0, 0, 0
    X = np.ascontiguousarray(rows[:, :, 0].T)
    Y = np.ascontiguousarray(rows[:, :, 1].T)
    # a knight move is at most sqrt(5) / sqrt(2) times the longest lattice edge
    longest = max(1.6 * max_move, max_spacing)
    cs = two_r + longest + 2.0 * max_spacing + 1e-6
    g = get_grid(geometry)
    W, H = workspace
    # the knight moves' clearance answers, kept for every search of the call
    ob = (np.full(1, float(need)), geometry.circles, geometry.verts, geometry.ptr, float(W),
          float(H), g.ptr, g.idx, g.box, g.nx, g.ny, g.cell, np.zeros(8 * V, np.int8))
    X, Y, _, done, work, groups = _rounds(X, Y, np.asarray(times, np.float64), gr, V, gv0,
                                          hs, goal, float(two_r), float(quantum), cs,
                                          float(max_spacing), int(budget), int(rounds), ob,
                                          int(group), int(exchanges), bool(sipp),
                                          max(0, int(restarts)))
    if done == 0:  # no way written: the rows as they were
        return rows, goal, done, work, groups
    # filled in place: a third of np.stack's time (0.2 against 0.65 ms at 400 robots)
    out = np.empty((X.shape[1], X.shape[0], 2))
    out[:, :, 0] = X.T
    out[:, :, 1] = Y.T
    return out, goal, done, work, groups
