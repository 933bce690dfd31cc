"""A fleet's assignment lowered over any-angle lengths, after the lattice bottleneck.

The assignment (:mod:`lamp.mrmp.assignment`) minimises the longest *lattice* distance.
The plan's robots do not keep to the lattice: the straight lines
(:mod:`lamp.mrmp.shortcut`) and the timed repair's knight moves bring a robot in up to
8 % sooner than its lattice distance, more where its lattice path bends often, less
where it runs along a lattice axis or diagonal. So the pair with the longest lattice
distance need not be the one that arrives last, and an assignment whose longest lattice
distance is larger may bring every robot in sooner. :func:`descend` changes the
assignment where that is so.

Each robot's *any-angle estimate* is the length of its lattice shortest path pulled
straight (:func:`pulled_length`: the path down the goal's exact distances, then from
each anchor the farthest later point of the path the straight segment to which keeps
the threshold ``r + margin`` from the obstacles and the border, exactly), but never
below its lattice distance over :data:`LIM` (the most by which an 8-connected path can
exceed the straight line in the open: a way that only a path pulled far from the
lattice shortens, through a passage where the lattice has no nodes, is not one the plan
takes). A robot's lattice distance is an upper bound on its estimate, so estimates are
made only for the robots whose lattice distance exceeds the largest estimate known.

Then, while the largest estimate ``a`` exceeds :data:`STOP` times the straight-line
floor (a lower bound on every plan's makespan), its robot ``i`` gives up its goal if an
alternating path of pairs whose estimates are all below ``a`` lets every goal keep a
robot: a breadth-first search from ``i``'s goal over the robots that could take it
(straight line below ``a``, lattice distance below ``a``, or below ``LIM a`` with an
estimate below ``a``), each passing on its own goal, until ``i`` itself takes one.
First over lattice distances alone (no estimate made), then with estimates; at most
:data:`ROUNDS` rounds. Every goal keeps exactly one robot, every robot at most one goal,
and the largest estimate never grows; the robots off the path keep their goals.

This changes which robot takes which goal, nothing else: the steps, repairs and checks
after it are those of any assignment, so every guarantee of the plan holds unchanged.
Deterministic (no clock, no randomness). Only fleets of more than
:data:`DESCEND_ABOVE` robots, so that smaller teams keep their plans.
"""

from __future__ import annotations

import math
import time

import numba as nb
import numpy as np

from lamp.mrmp.goal_distances import EPS
from lamp.mrmp.heuristic_reads import goal_views, read_in
from lamp.mrmp.obstacle_grid import get_grid, grid_clear_segments

__all__ = ["DESCEND_ABOVE", "ESTIMATES", "LIM", "ROUNDS", "STOP", "descend", "lattice_walk",
           "lower_assignment", "obstacles_of", "pull_straight", "pulled_length",
           "warm_descent"]

#: Fleets of more robots than this get the descent.
DESCEND_ABOVE = 100
#: The most by which an 8-connected lattice path exceeds the straight line in the open
#: (``(sqrt(2) - 1) ... = 1 / cos(22.5 deg)``).
LIM = 1.0 / math.cos(math.pi / 8.0)
#: The descent stops once the largest estimate is at most this times the straight floor.
STOP = 1.45
#: The most rounds (robots moved off their goals) of one descent.
ROUNDS = 16
#: The most pairs' estimates made in one round's search.
ESTIMATES = 64
#: Segments checked at once when a path is pulled straight.
_CHUNK = 8


@nb.njit(cache=True)
def lattice_walk(i: int, m: int, gr: tuple, V: int, gv0: int, hs: tuple, pts: np.ndarray) -> int:
    """Robot i's lattice shortest path to goal m, written to ``pts`` (the caller's
    buffer: at most ``pts.shape[0]`` points); returns the points written, 0 when the
    goal is not reachable or the buffer too short. Each step goes to the neighbour (or
    the goal vertex) of least edge length plus distance, the first such in order, among
    the nodes the goal's search has settled: the best one always is (its distance is
    at least a lattice step below the current node's, which is settled), so no search
    grows here."""
    coords, nbr, dlen, xptr, xidx = gr
    va, vb, sdone, sval = hs[11], hs[12], hs[9], hs[10]
    dd, dn, a0, b0, na, nbw = goal_views(m, hs)
    goal_v = gv0 + m
    u = V + i
    n = 0
    while True:
        if n >= pts.shape[0]:
            return 0
        pts[n, 0], pts[n, 1] = coords[u, 0], coords[u, 1]
        n += 1
        if u == goal_v:
            return n
        best, nxt = np.inf, -1
        if u < V:
            for k in range(8):
                w = nbr[u, k]
                if w >= 0:
                    h = read_in(m, w, V, va, vb, sdone, sval, dd, dn, a0, b0, na, nbw)
                    if h >= 0.0 and dlen[k] + h < best:
                        best, nxt = dlen[k] + h, w
        for e in range(xptr[u], xptr[u + 1]):
            w = xidx[e]
            if w < V or w == goal_v:
                h = 0.0 if w == goal_v else read_in(m, w, V, va, vb, sdone, sval, dd, dn,
                                                    a0, b0, na, nbw)
                c = math.hypot(coords[u, 0] - coords[w, 0], coords[u, 1] - coords[w, 1])
                if h >= 0.0 and c + h < best:
                    best, nxt = c + h, w
        if nxt < 0 or not np.isfinite(best):
            return 0
        u = nxt


@nb.njit(cache=True)
def pull_straight(pts: np.ndarray, n: int, ob: tuple) -> float:
    """The length of the points ``pts[:n]`` pulled straight: from each anchor on to the
    last point before the first that the straight segment from it does not reach clear
    of the obstacles (the next point at least: consecutive points are linked by checked
    moves). The segments are checked :data:`_CHUNK` at a time."""
    need, circles, verts, vptr, W, H, gptr, gidx, box, gnx, gny, gcell = ob
    sa = np.empty((_CHUNK, 2))
    sb = np.empty((_CHUNK, 2))
    needs = np.full(_CHUNK, need[0])
    total = 0.0
    a = 0
    while a < n - 1:
        j = a + 1  # the last point reached so far
        while j + 1 < n:
            c = min(_CHUNK, n - 1 - j)
            for q in range(c):
                sa[q, 0], sa[q, 1] = pts[a, 0], pts[a, 1]
                sb[q, 0], sb[q, 1] = pts[j + 1 + q, 0], pts[j + 1 + q, 1]
            ok = grid_clear_segments(sa[:c], sb[:c], needs[:c], circles, verts, vptr, W, H,
                                     gptr, gidx, box, gnx, gny, gcell)
            q = 0
            while q < c and ok[q]:
                q += 1
            j += q
            if q < c:
                break
        total += math.hypot(pts[j, 0] - pts[a, 0], pts[j, 1] - pts[a, 1])
        a = j
    return total


@nb.njit(cache=True)
def pulled_length(i: int, m: int, gr: tuple, V: int, gv0: int, hs: tuple, ob: tuple,
                  pts: np.ndarray) -> float:
    """Robot i's lattice shortest path to goal m pulled straight (module docstring);
    inf when there is none (or it has more points than the buffer ``pts``)."""
    n = lattice_walk(i, m, gr, V, gv0, hs, pts)
    if n == 0:
        return np.inf
    return pull_straight(pts, n, ob)


@nb.njit(cache=True)
def _estimate(i: int, m: int, lat: float, gr: tuple, V: int, gv0: int, hs: tuple,
              ob: tuple, pts: np.ndarray) -> float:
    """The any-angle estimate of robot i for goal m, whose lattice distance is ``lat``."""
    if not np.isfinite(lat):
        return np.inf
    return max(pulled_length(i, m, gr, V, gv0, hs, ob, pts), lat / LIM)


@nb.njit(cache=True)
def _lazy_max(a: np.ndarray, known: np.ndarray, goal: np.ndarray, gr: tuple, V: int,
              gv0: int, hs: tuple, ob: tuple, pts: np.ndarray, made: np.ndarray) -> int:
    """The robot of the largest estimate, ``a`` holding each robot's estimate where
    ``known``, else its lattice distance (an upper bound), estimates made as needed
    (counted in ``made[0]``)."""
    while True:
        i = int(np.argmax(a))
        if known[i] or goal[i] < 0:
            return i
        a[i] = _estimate(i, goal[i], a[i], gr, V, gv0, hs, ob, pts)
        known[i] = True
        made[0] += 1


@nb.njit(cache=True)
def _fill(g: int, ptr: np.ndarray, pidx: np.ndarray, plat: np.ndarray, gr: tuple, V: int,
          gv0: int, hs: tuple) -> None:
    """Goal g's pairs' lattice distances as far as its search has settled them (inf
    beyond: :func:`lamp.mrmp.heuristic_reads.hval_below`'s values, no search grown)."""
    coords, _, _, xptr, xidx = gr
    va, vb, sdone, sval = hs[11], hs[12], hs[9], hs[10]
    dd, dn, a0, b0, na, nbw = goal_views(g, hs)
    for k in range(ptr[g], ptr[g + 1]):
        v = V + pidx[k]
        best = np.inf
        for e in range(xptr[v], xptr[v + 1]):
            n = xidx[e]
            dx = coords[v, 0] - coords[n, 0]
            dy = coords[v, 1] - coords[n, 1]
            ln = math.sqrt(dx * dx + dy * dy)  # as hval_below, bit for bit
            if n < V:
                h = read_in(g, n, V, va, vb, sdone, sval, dd, dn, a0, b0, na, nbw)
                c = ln + h if h >= 0.0 else np.inf
            elif n == gv0 + g:
                c = ln + EPS
            else:
                continue
            best = min(best, c)
        plat[k] = best


@nb.njit(cache=True)
def _augment(i0: int, thr: float, with_est: bool, goal: np.ndarray, holder: np.ndarray,
             ptr: np.ndarray, pidx: np.ndarray, pstr: np.ndarray, plat: np.ndarray,
             pest: np.ndarray, filled: np.ndarray, left: np.ndarray, a: np.ndarray,
             known: np.ndarray, lat: np.ndarray, gr: tuple, V: int, gv0: int, hs: tuple, ob: tuple,
             pts: np.ndarray) -> int:
    """One round (module docstring): robot i0 off its goal along an alternating path of
    pairs below ``thr`` (breadth first, over estimates when ``with_est``, as long as
    ``left[0]`` allows more); the robots moved, 0 when there is no such path."""
    N, M = goal.shape[0], ptr.shape[0] - 1
    prev = np.full(N, -1, np.int64)  # the pair by which each robot was reached
    seen = np.zeros(M, np.bool_)
    queue = np.empty(M, np.int64)
    m0 = goal[i0]
    queue[0], seen[m0] = m0, True
    head, tail, end = 0, 1, -1
    while head < tail and end < 0:
        g = queue[head]
        head += 1
        if not filled[g]:
            _fill(g, ptr, pidx, plat, gr, V, gv0, hs)
            filled[g] = True
        for k in range(ptr[g], ptr[g + 1]):
            j = pidx[k]
            if prev[j] >= 0 or pstr[k] >= thr:
                continue
            ok = plat[k] < thr
            if not ok and with_est and plat[k] < LIM * thr:
                if np.isnan(pest[k]) and left[0] > 0:
                    left[0] -= 1
                    pest[k] = _estimate(j, g, plat[k], gr, V, gv0, hs, ob, pts)
                ok = pest[k] < thr  # (False while not estimated: nan)
            if not ok:
                continue
            prev[j] = k
            if j == i0 or goal[j] < 0:
                end = j
                break
            if not seen[goal[j]]:
                seen[goal[j]] = True
                queue[tail] = goal[j]
                tail += 1
    if end < 0:
        return 0
    j, moved = end, 0
    while True:
        k = prev[j]
        g = _goal_of_pair(k, ptr)
        h = holder[g]
        goal[j], holder[g], lat[j] = g, j, plat[k]
        known[j] = not np.isnan(pest[k])
        a[j] = pest[k] if known[j] else plat[k]
        moved += 1
        if g == m0:
            break
        j = h
    if end != i0:
        goal[i0], a[i0], known[i0], lat[i0] = -1, -np.inf, True, 0.0
    return moved


@nb.njit(cache=True)
def _goal_of_pair(k: int, ptr: np.ndarray) -> int:
    """The goal of pair k (``ptr``: the pairs' offsets by goal)."""
    return int(np.searchsorted(ptr, k, side="right")) - 1


@nb.njit(cache=True)
def _descend(goal: np.ndarray, a: np.ndarray, floor: float, ptr: np.ndarray,
             pidx: np.ndarray, pstr: np.ndarray, gr: tuple, V: int,
             gv0: int, hs: tuple, ob: tuple, pts: np.ndarray, stop: float,
             rounds: int, estimates: int) -> tuple[np.ndarray, int, int]:
    """The descent's rounds on ``goal`` in place (``a``: the robots' lattice distances,
    ``ptr``/``pidx``/``pstr``: the goal-robot pairs whose straight line is below the
    first largest estimate); the lattice distances of the final pairs, the rounds done
    and the estimates made."""
    N, M = goal.shape[0], ptr.shape[0] - 1
    lat = a.copy()
    known = goal < 0
    a[known] = -np.inf
    holder = np.full(M, -1, np.int64)
    for i in range(N):
        if goal[i] >= 0:
            holder[goal[i]] = i
    P = pidx.shape[0]
    plat = np.full(P, np.inf)
    pest = np.full(P, np.nan)
    filled = np.zeros(M, np.bool_)
    done = 0
    made = np.zeros(1, np.int64)
    while done < rounds:
        i0 = _lazy_max(a, known, goal, gr, V, gv0, hs, ob, pts, made)
        thr = a[i0]
        if goal[i0] < 0 or thr <= stop * floor:
            break
        left = np.full(1, estimates, np.int64)
        moved = _augment(i0, thr, False, goal, holder, ptr, pidx, pstr, plat, pest, filled,
                         left, a, known, lat, gr, V, gv0, hs, ob, pts)
        if moved == 0:
            moved = _augment(i0, thr, True, goal, holder, ptr, pidx, pstr, plat, pest,
                             filled, left, a, known, lat, gr, V, gv0, hs, ob, pts)
        if moved == 0:
            break
        done += 1
    for i in range(N):
        if goal[i] < 0:
            lat[i] = 0.0
    return lat, done, int(made[0]) + int((~np.isnan(pest)).sum())


def obstacles_of(space) -> tuple:
    """The obstacle arrays :func:`pull_straight` takes: the space's threshold as the
    clearance a segment keeps, its geometry and border, and its obstacle grid."""
    g = get_grid(space.geometry)
    W, H = space.workspace
    geo = space.geometry
    return (np.full(1, float(space.threshold)), geo.circles, geo.verts, geo.ptr, float(W),
            float(H), g.ptr, g.idx, g.box, g.nx, g.ny, g.cell)


def descend(goal: np.ndarray, cost: np.ndarray, floor: float, gr: tuple, V: int,
            hs: tuple, S: np.ndarray, G: np.ndarray, space, stop: float = STOP,
            rounds: int = ROUNDS, estimates: int = ESTIMATES
            ) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The assignment ``goal`` (robot -> goal, -1 none; ``cost``: the lattice distances)
    lowered over any-angle estimates (module docstring); ``floor``: a lower bound on the
    straight-line bottleneck; ``space``: the :class:`~lamp.geometry.robot_space.
    RobotSpace` planned in; ``stop``, ``rounds``, ``estimates``: :data:`STOP`,
    :data:`ROUNDS` and :data:`ESTIMATES`. Returns the new goals and lattice distances (copies), the
    rounds done and the estimates made."""
    from lamp.mrmp.near_pairs import near_pairs

    N, M = len(S), len(G)
    goal = np.array(goal, dtype=np.int64)
    a = np.where(goal >= 0, np.asarray(cost, dtype=np.float64), -np.inf)
    if rounds <= 0 or M == 0 or not np.isfinite(a).any() or a.max() <= stop * floor:
        return goal, np.asarray(cost, dtype=np.float64).copy(), 0, 0
    ob = obstacles_of(space)
    top = float(a.max())
    pts = np.empty((int(LIM * top / hs.step) + 8, 2))
    # the pairs that can be below the first largest estimate, which is at most ``top``
    pm, pi, pd = near_pairs(G, S, top, strict=True)
    ptr = np.searchsorted(pm, np.arange(M + 1)).astype(np.int64)
    lat, done, made = _descend(goal, a, float(floor), ptr, pi.astype(np.int64),
                               pd.astype(np.float64), gr, V, V + N, hs, ob, pts,
                               float(stop), int(rounds), int(estimates))
    return goal, lat, done, made


def lower_assignment(asg, gr: tuple, V: int, hs: tuple, S: np.ndarray, G: np.ndarray,
                     space, stats: dict) -> tuple[np.ndarray, np.ndarray]:
    """The goals and lattice distances of the assignment ``asg``
    (:class:`lamp.mrmp.assignment.Assignment`), descended (:func:`descend`) for fleets of
    more than :data:`DESCEND_ABOVE` robots assigned by the bottleneck (``asg.floor``
    set); the rounds, estimates and time in ``stats``."""
    if len(S) <= DESCEND_ABOVE or asg.floor <= 0.0:
        return asg.goal, asg.cost
    clock = time.perf_counter()
    goal, cost, stats["descent_rounds"], stats["descent_estimates"] = descend(
        asg.goal, asg.cost, asg.floor, gr, V, hs, S, G, space, STOP, ROUNDS, ESTIMATES)
    stats["time_descent"] = time.perf_counter() - clock
    return goal, cost


def warm_descent(space) -> None:
    """Compile (or load) the descent's kernels on two robots of ``space`` swapped across
    it (its corners must be free: :func:`lamp.mrmp.gspi.warmup`'s scene)."""
    from lamp.mrmp.distance_field import get_lattice
    from lamp.mrmp.goal_distances import GoalDistances, start_costs
    from lamp.mrmp.links import Links, link_special_vertices

    W, H = space.workspace
    S = np.array([[0.1, 0.1], [W - 0.1, H - 0.1]])
    G = S[::-1].copy()
    lat = get_lattice(space, 0.05)
    c = space.clearance(S, exact=True)
    links = link_special_vertices(space, lat, S, G, c, c[::-1].copy(), 0.075, {})
    if isinstance(links, Links):
        hs = GoalDistances.build(links.goal_links, G, lat, 4)
        C = start_costs(0, 2, 2, links.graph, lat.V, hs)
        goal = np.arange(2, dtype=np.int64)
        descend(goal, C.diagonal().copy(), 0.0, links.graph, lat.V, hs, S, G, space, 0.0,
                1, 1)
