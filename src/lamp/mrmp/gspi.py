"""Gspi: anonymous multi-robot motion planning by Goal Swapping with Priority Inheritance.

N disk robots of radius r move from continuous starts to M <= N continuous goal points;
any robot may take any goal. The planner works on the free 8-connected lattice of a
:class:`~lamp.geometry.robot_space.RobotSpace` (step ``L``, default 5 cm), extended by one
*special vertex* per start and per goal, each linked by checked straight motions to the
lattice nodes within ``link_radius`` (and starts to goals directly when close).

Each time step (GCo's Gspi, with the fixes listed in the issue):

1. goal swapping: for every pair of robots, swap their goals (and priorities, which travel
   with goals) when that lowers the sum of their heuristic distances; a robot without a
   goal counts 0, so an idle robot closer to a goal takes it over;
2. one PIBT step (Okumura et al., "Priority inheritance with backtracking", AIJ 2022,
   Algorithm 1, ``funcPIBT``), iterative with an explicit stack: robots in priority order pick
   the candidate (neighbours and *wait*) that most lowers their heuristic; when a chosen
   move would hit a robot that has not decided yet, that robot decides first (priority
   inheritance) and the parent re-checks, taking its next candidate on failure
   (backtracking). Continuous-space changes: a move is checked against every decided
   robot's whole linear motion (robot-robot distance >= 2r over the step, exact), and
   descendants also keep clear of their ancestors' current positions (the continuous
   form of PIBT's no-swap rule), which keeps "stay" always valid for a failed robot; a
   child with no move compatible with its ancestors' motions may still *yield* (move
   clear of their positions) so that the way opens for the next step;
3. priorities: robots at their goal (or without one) reset to their fractional tie-break
   part, the others grow by 1.

Heuristic: one Dijkstra per goal over the lattice (8-connected, diagonal moves cost
``L * sqrt(2)``), seeded with the goal's links and *resumed lazily* only as far as the
queries need (pypibt's lazy distance table, in compiled code): a 3-robot call near the
object settles a few hundred nodes. Initial assignment: ``linear_sum_assignment`` on
these distances (unreachable pairs excluded; a goal no robot can reach is reported at
once). Lattices: 5 cm first; when that fails in a way a finer lattice can fix (a goal or
start that cannot be linked, a passage narrower than the lattice, a stall) 3 cm and then
2 cm are tried while time is left.

Output: the vertex sequence, all-wait steps dropped, each step cut into the fewest equal
sub-steps that keep every robot's consecutive rows <= ``max_spacing`` apart (linear
motion within a step is exactly what was checked, so the rows are a faithful sampling).

Obstacle safety: lattice edges are checked conservatively over the whole motion
(:mod:`lamp.mrmp.distance_field`); links are checked with the exact segment clearance.
Tolerances (documented in :func:`plan_paths`): a goal may lie up to ``goal_tolerance``
closer to an obstacle than the free threshold ``r + margin``; a start up to
``start_tolerance``. The rule for every motion is *non-worsening*: clearance along it is
at least ``min(threshold, clearance at its ends)``; for robot pairs, distance along a step
is at least ``min(2r, distance at the step start)``, and two robots arriving at two goals
closer than 2r (within ``goal_tolerance``) may end at that distance.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numba as nb
import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment

from lamp.geometry.kernels import point_segment_distance
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.distance_field import Lattice, get_lattice
from lamp.scene.model import Scene

__all__ = ["MRMPPlan", "plan_paths", "warmup"]

_BIG = 1e9
_EPS = 1e-6
_UNDECIDED, _TENTATIVE, _DECIDED = 0, 1, 2


@dataclass
class MRMPPlan:
    """Result of :func:`plan_paths`.

    success: every goal reached by exactly one robot, all motions checked.
    paths: (N, T, 2) synchronised positions (row t of every robot is the same instant),
        consecutive rows at most ``max_spacing`` (0.02 m) apart; ``paths[:, 0]`` are the
        starts. On failure: the motion computed so far (never to be executed as a plan).
    goal_of: (N,) goal index per robot at the end, -1 for robots without a goal.
    reason: empty on success, else why it failed.
    iterations: Gspi time steps taken.
    time_s: wall-clock time of the call.
    stats: extra figures (lattice size, link counts, steps removed ...).
    """

    success: bool
    paths: np.ndarray
    goal_of: np.ndarray
    reason: str = ""
    iterations: int = 0
    time_s: float = 0.0
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def n_steps(self) -> int:
        """Number of synchronised rows T."""
        return int(self.paths.shape[1])


# --------------------------------------------------------------------------------------
# Compiled core
# --------------------------------------------------------------------------------------


@nb.njit(cache=True, inline="always")
def _hash01(seed: int, t: int, i: int, c: int) -> float:
    """Deterministic uniform [0, 1) from integers (splitmix64 finaliser)."""
    z = (
        np.uint64(seed) * np.uint64(0x9E3779B97F4A7C15)
        + np.uint64(t) * np.uint64(0xBF58476D1CE4E5B9)
        + np.uint64(i) * np.uint64(0x94D049BB133111EB)
        + np.uint64(c)
    )
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    z = z ^ (z >> np.uint64(31))
    return float(z >> np.uint64(11)) * (1.0 / 9007199254740992.0)


@nb.njit(cache=True)
def _conflict(
    ax: float, ay: float, bx: float, by: float,
    cx: float, cy: float, dx: float, dy: float,
    two_r: float, both_goal_end: bool,
) -> bool:
    """Whether motion a->b of one robot and c->d of another (same time span, linear)
    come closer than allowed: min distance < min(2r, start distance[, end distance
    when both end on goals])."""
    d0x = ax - cx
    d0y = ay - cy
    d1x = bx - dx
    d1y = by - dy
    thr = two_r
    d0 = math.sqrt(d0x * d0x + d0y * d0y)
    if d0 < thr:
        thr = d0
    if both_goal_end:
        d1 = math.sqrt(d1x * d1x + d1y * d1y)
        if d1 < thr:
            thr = d1
    # closest approach: distance of the origin to the relative-offset segment d0 -> d1
    return point_segment_distance(0.0, 0.0, d0x, d0y, d1x, d1y) < thr - 1e-9


# ---- lazy heuristic: one resumable Dijkstra per goal ---------------------------------
# State ``hs`` = (dist (M, V), pos (M, V), heap (M, V), hsize (M,), sdone (M, N+M),
# sval (M, N+M)): lattice distance to goal m (seeded with the goal's links), heap position
# of each node (-1 unseen, -2 settled), an indexed binary heap per goal, and memoised
# values for the special (start / goal) vertices. A value is computed only when asked
# for (as pypibt's lazy DistTable), so a 3-robot call near the object settles a few
# hundred nodes instead of the whole map.


@nb.njit(cache=True)
def _heap_up(m: int, i: int, dist: np.ndarray, pos: np.ndarray, heap: np.ndarray) -> None:
    v = heap[m, i]
    dv = dist[m, v]
    while i > 0:
        p = (i - 1) >> 1
        u = heap[m, p]
        if dist[m, u] <= dv:
            break
        heap[m, i] = u
        pos[m, u] = i
        i = p
    heap[m, i] = v
    pos[m, v] = i


@nb.njit(cache=True)
def _heap_pop(m: int, dist: np.ndarray, pos: np.ndarray, heap: np.ndarray,
              hsize: np.ndarray) -> int:
    top = heap[m, 0]
    n = hsize[m] - 1
    hsize[m] = n
    pos[m, top] = -2
    if n > 0:
        v = heap[m, n]
        dv = dist[m, v]
        i = 0
        while True:
            c = 2 * i + 1
            if c >= n:
                break
            if c + 1 < n and dist[m, heap[m, c + 1]] < dist[m, heap[m, c]]:
                c += 1
            u = heap[m, c]
            if dist[m, u] >= dv:
                break
            heap[m, i] = u
            pos[m, u] = i
            i = c
        heap[m, i] = v
        pos[m, v] = i
    return top


@nb.njit(cache=True, inline="always")
def _heap_lower(m: int, v: int, d: float, dist: np.ndarray, pos: np.ndarray, heap: np.ndarray,
                hsize: np.ndarray) -> None:
    """Set goal m's distance of vertex v to the smaller value d and restore the heap
    (v is pushed first when it has never been queued, ``pos == -1``)."""
    dist[m, v] = d
    if pos[m, v] == -1:
        heap[m, hsize[m]] = v
        pos[m, v] = hsize[m]
        hsize[m] += 1
    _heap_up(m, pos[m, v], dist, pos, heap)


@nb.njit(cache=True)
def _seed_goal(m: int, nodes: np.ndarray, cost: np.ndarray, hs: tuple) -> None:
    dist, pos, heap, hsize, _, _ = hs
    for k in range(nodes.shape[0]):
        v = nodes[k]
        if cost[k] < dist[m, v]:
            _heap_lower(m, v, cost[k], dist, pos, heap, hsize)


@nb.njit(cache=True)
def _lattice_h(m: int, v: int, nbr: np.ndarray, dlen: np.ndarray, hs: tuple) -> float:
    """Distance from lattice node v to goal m, running goal m's Dijkstra until v settles."""
    dist, pos, heap, hsize, _, _ = hs
    while pos[m, v] != -2 and hsize[m] > 0:
        u = _heap_pop(m, dist, pos, heap, hsize)
        du = dist[m, u]
        for e in range(8):
            w = nbr[u, e]
            if w < 0 or pos[m, w] == -2:
                continue
            nd = du + dlen[e]
            if nd < dist[m, w]:
                _heap_lower(m, w, nd, dist, pos, heap, hsize)
    if pos[m, v] == -2:
        return dist[m, v]
    return np.inf


@nb.njit(cache=True)
def _hval(m: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    """Heuristic distance of vertex v (lattice or special) to goal m."""
    coords, nbr, dlen, xptr, xidx = gr
    if v < V:
        return _lattice_h(m, v, nbr, dlen, hs)
    _, _, _, _, sdone, sval = hs
    k = v - V
    if sdone[m, k]:
        return sval[m, k]
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
                c = ln + _lattice_h(m, n, nbr, dlen, hs)
            elif n == gv0 + m:
                c = ln + _EPS
            else:
                continue
            if c < best:
                best = c
    sdone[m, k] = True
    sval[m, k] = best
    return best


@nb.njit(cache=True)
def _h(goal: np.ndarray, i: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple) -> float:
    g = goal[i]
    if g < 0:
        return 0.0
    return _hval(g, v, gr, V, gv0, hs)


@nb.njit(cache=True)
def _build_cands(
    i: int, v: int, gr: tuple, V: int, gv0: int, hs: tuple, goal: np.ndarray, seed: int,
    t: int, cand: np.ndarray, ncand: np.ndarray,
) -> None:
    """Candidates of robot i at vertex v sorted by heuristic (wait included); ties are
    broken by a seeded hash; a robot without a goal tries waiting first."""
    _, nbr, _, xptr, xidx = gr
    keys = np.empty(cand.shape[1])
    cand[i, 0] = v
    keys[0] = -1.0 if goal[i] < 0 else _h(goal, i, v, gr, V, gv0, hs)
    n = 1
    if v < V:
        for e in range(8):
            u = nbr[v, e]
            if u >= 0:
                cand[i, n] = u
                n += 1
    for k in range(xptr[v], xptr[v + 1]):
        cand[i, n] = xidx[k]
        n += 1
    for k in range(1, n):
        hv = _h(goal, i, cand[i, k], gr, V, gv0, hs)
        if hv == np.inf:
            keys[k] = np.inf
        else:
            keys[k] = hv + 1e-9 * _hash01(seed, t, i, cand[i, k])
    if goal[i] >= 0:
        keys[0] += 1e-9 * _hash01(seed, t, i, v)
    # insertion sort (n <= ~20)
    for a in range(1, n):
        kk = keys[a]
        cc = cand[i, a]
        b = a - 1
        while b >= 0 and keys[b] > kk:
            keys[b + 1] = keys[b]
            cand[i, b + 1] = cand[i, b]
            b -= 1
        keys[b + 1] = kk
        cand[i, b + 1] = cc
    # drop candidates with infinite heuristic except waiting (they lead nowhere useful)
    m = n
    while m > 1 and keys[m - 1] == np.inf and cand[i, m - 1] != v:
        m -= 1
    ncand[i] = m


@nb.njit(cache=True)
def _pibt_step(
    gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
    prio: np.ndarray, two_r: float, seed: int, t: int, nxt: np.ndarray,
    cand: np.ndarray, ncand: np.ndarray, ci: np.ndarray, status: np.ndarray,
    stack: np.ndarray, mode: np.ndarray,
) -> None:
    """One PIBT step (priority inheritance with backtracking), iterative.

    Continuous-space addition (*yield*): a robot that inherited priority and found no
    move compatible with its ancestors' intended motions scans its candidates again
    checking only the ancestors' current positions. A move found that way clears the way
    for the next step while the ancestor, which re-checks against it, waits or detours.
    Without it two robots 10 cm apart whose simultaneous moves would graze each other
    could block each other forever (the parent's wait always beating its detours).
    """
    coords = gr[0]
    N = cur.shape[0]
    for k in range(N):
        status[k] = _UNDECIDED
        nxt[k] = cur[k]
        mode[k] = 0
    order = np.argsort(-prio)
    for oi in range(N):
        r0 = order[oi]
        if status[r0] != _UNDECIDED:
            continue
        status[r0] = _TENTATIVE
        _build_cands(r0, cur[r0], gr, V, gv0, hs, goal, seed, t, cand, ncand)
        ci[r0] = 0
        stack[0] = r0
        sp = 1
        while sp > 0:
            i = stack[sp - 1]
            if ci[i] >= ncand[i]:
                if mode[i] == 0 and sp > 1:
                    mode[i] = 1  # yield pass (see docstring)
                    ci[i] = 0
                    continue
                nxt[i] = cur[i]  # every candidate failed: wait (always valid, see module doc)
                status[i] = _DECIDED
                sp -= 1
                continue
            c = cand[i, ci[i]]
            if mode[i] == 1 and c == cur[i]:
                ci[i] += 1
                continue
            nxt[i] = c
            ax = coords[cur[i], 0]
            ay = coords[cur[i], 1]
            bx = coords[c, 0]
            by = coords[c, 1]
            c_goal = c >= gv0
            bad = False
            blocker = -1
            for k in range(N):
                if k == i:
                    continue
                sk = status[k]
                px = coords[cur[k], 0]
                py = coords[cur[k], 1]
                stay_goal = c_goal and cur[k] >= gv0
                if sk == _UNDECIDED:
                    if blocker < 0 and _conflict(ax, ay, bx, by, px, py, px, py, two_r,
                                                 stay_goal):
                        blocker = k
                elif sk == _DECIDED:
                    qx = coords[nxt[k], 0]
                    qy = coords[nxt[k], 1]
                    if _conflict(ax, ay, bx, by, px, py, qx, qy, two_r,
                                 c_goal and nxt[k] >= gv0):
                        bad = True
                        break
                else:  # tentative ancestor: its position now and its intended motion
                    qx = coords[nxt[k], 0]
                    qy = coords[nxt[k], 1]
                    if _conflict(ax, ay, bx, by, px, py, px, py, two_r, stay_goal) or (
                        mode[i] == 0
                        and _conflict(ax, ay, bx, by, px, py, qx, qy, two_r,
                                      c_goal and nxt[k] >= gv0)
                    ):
                        bad = True
                        break
            if bad:
                ci[i] += 1
                continue
            if blocker >= 0:
                # priority inheritance: the blocker decides first, then i re-checks c
                status[blocker] = _TENTATIVE
                _build_cands(blocker, cur[blocker], gr, V, gv0, hs, goal, seed, t, cand, ncand)
                ci[blocker] = 0
                mode[blocker] = 0
                stack[sp] = blocker
                sp += 1
                continue
            status[i] = _DECIDED
            sp -= 1


@nb.njit(cache=True)
def _swap_goals(gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
                prio: np.ndarray) -> int:
    """Pairwise goal swaps that lower the summed heuristic (priorities travel along)."""
    N = cur.shape[0]
    nswap = 0
    for i in range(N):
        for j in range(i + 1, N):
            gi = goal[i]
            gj = goal[j]
            if gi < 0 and gj < 0:
                continue
            now = 0.0
            sw = 0.0
            if gi >= 0:
                now += _hval(gi, cur[i], gr, V, gv0, hs)
                sw += _hval(gi, cur[j], gr, V, gv0, hs)
            if gj >= 0:
                now += _hval(gj, cur[j], gr, V, gv0, hs)
                sw += _hval(gj, cur[i], gr, V, gv0, hs)
            if sw < now - 1e-9:
                goal[i] = gj
                goal[j] = gi
                p = prio[i]
                prio[i] = prio[j]
                prio[j] = p
                nswap += 1
    return nswap


@nb.njit(cache=True)
def _run_steps(
    gr: tuple, V: int, gv0: int, hs: tuple, cur: np.ndarray, goal: np.ndarray,
    prio: np.ndarray, two_r: float, seed: int, swap: bool, hist: np.ndarray,
    hsum: np.ndarray, t0: int, t1: int, maxc: int,
) -> tuple[int, bool]:
    """Run Gspi steps t0..t1-1; hist[t+1] receives the vertices after step t and
    hsum[t+1] the summed heuristic. Returns (rows filled - 1, all goals reached)."""
    N = cur.shape[0]
    nxt = np.empty(N, dtype=np.int64)
    cand = np.empty((N, maxc), dtype=np.int64)
    ncand = np.zeros(N, dtype=np.int64)
    ci = np.zeros(N, dtype=np.int64)
    status = np.zeros(N, dtype=np.int64)
    stack = np.empty(N, dtype=np.int64)
    mode = np.zeros(N, dtype=np.int64)
    for t in range(t0, t1):
        done = True
        for i in range(N):
            if goal[i] >= 0 and cur[i] != gv0 + goal[i]:
                done = False
                break
        if done:
            return t, True
        if swap:
            _swap_goals(gr, V, gv0, hs, cur, goal, prio)
        _pibt_step(gr, V, gv0, hs, cur, goal, prio, two_r, seed, t, nxt, cand, ncand, ci,
                   status, stack, mode)
        s = 0.0
        for i in range(N):
            cur[i] = nxt[i]
            hist[t + 1, i] = nxt[i]
            g = goal[i]
            if g < 0 or cur[i] == gv0 + g:
                prio[i] = prio[i] - math.floor(prio[i])
            else:
                prio[i] += 1.0
                s += min(_hval(g, cur[i], gr, V, gv0, hs), 1e6)
        hsum[t + 1] = s
    done = True
    for i in range(N):
        if goal[i] >= 0 and cur[i] != gv0 + goal[i]:
            done = False
            break
    return t1, done


@nb.njit(cache=True)
def _start_costs(gr: tuple, V: int, gv0: int, hs: tuple, N: int, m: int) -> np.ndarray:
    """(N,) heuristic distance from each start vertex to goal m."""
    C = np.empty(N)
    for i in range(N):
        C[i] = _hval(m, V + i, gr, V, gv0, hs)
    return C


# --------------------------------------------------------------------------------------
# Python driver
# --------------------------------------------------------------------------------------


def _array2(x: ArrayLike, name: str) -> np.ndarray:
    try:
        a = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an (n, 2) array of numbers: {exc}") from exc
    if a.ndim == 1 and a.size == 0:
        a = a.reshape(0, 2)
    if a.ndim != 2 or a.shape[1] != 2:
        raise ValueError(f"{name} must have shape (n, 2), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got non-finite values")
    return a


def _check_points(
    space: RobotSpace, pts: np.ndarray, name: str, tol: float
) -> np.ndarray:
    """Exact clearance of each point; raises when a point is deeper than ``tol`` inside
    the threshold or two points overlap by more than ``tol``."""
    W, H = space.workspace
    outside = (pts[:, 0] < 0) | (pts[:, 0] > W) | (pts[:, 1] < 0) | (pts[:, 1] > H)
    if outside.any():
        k = int(np.nonzero(outside)[0][0])
        raise ValueError(f"{name}[{k}] = {pts[k].tolist()} lies outside the workspace {W}x{H}")
    clr = space.clearance(pts, exact=True)
    bad = clr < space.threshold - tol
    if bad.any():
        k = int(np.nonzero(bad)[0][0])
        where = "inside an obstacle" if clr[k] < 0 else "overlapping an obstacle or the border"
        raise ValueError(
            f"{name}[{k}] = {pts[k].tolist()} is {where}: clearance {clr[k]:.4f} m < "
            f"required {space.threshold:.4f} m - tolerance {tol:g} m"
        )
    if len(pts) > 1:
        d = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(d, np.inf)
        close = d < 2 * space.radius - tol
        if close.any():
            a, b = (int(v) for v in np.argwhere(close)[0])
            raise ValueError(
                f"{name}[{a}] and {name}[{b}] overlap: distance {d[a, b]:.4f} m < 2r = "
                f"{2 * space.radius:.4f} m - tolerance {tol:g} m"
            )
    return clr


_WARM = False


def warmup() -> None:
    """Compile (or load from Numba's cache) every kernel on a tiny problem.

    Called by the first :func:`plan_paths` of a process *before* its clock starts, so that
    compilation (about 20 s the very first time, about 0.5 s loading from the on-disk
    cache later) never eats into ``time_limit``.
    """
    global _WARM
    if _WARM:
        return
    _WARM = True
    from lamp.scene.model import Circle, Obstacle, Rectangle

    sc = Scene("warmup", (0.6, 0.6), ((0.1, 0.1), (0.1, 0.5)), (),
               (Obstacle(Circle(0.05), (0.3, 0.3, 0.0)),
                Obstacle(Rectangle((0.05, 0.05)), (0.5, 0.1, 0.0))))
    sp = RobotSpace.from_scene(sc)
    sp.is_free(np.array([[0.2, 0.2]]))
    sp.clearance(np.array([[0.2, 0.2]]))
    sp.nearest_free(np.array([0.3, 0.3]))
    plan_paths(sc, sc.robot_starts_array, np.array([[0.5, 0.5], [0.1, 0.3]]), time_limit=1e6)


def plan_paths(
    scene: Scene,
    starts: ArrayLike,
    goals: ArrayLike,
    object_poses: ArrayLike | None = None,
    extra_obstacles: Any = (),
    time_limit: float = 5.0,
    *,
    space: RobotSpace | None = None,
    seed: int = 0,
    lattice_step: float | tuple[float, ...] = (0.05, 0.03, 0.02),
    link_radius: float | None = None,
    goal_swapping: bool = True,
    max_spacing: float = 0.02,
    goal_tolerance: float = 0.006,
    start_tolerance: float = 0.01,
    max_steps: int | None = None,
    stall_steps: int | None = None,
    initial_goal_of: ArrayLike | None = None,
) -> MRMPPlan:
    """Anonymous multi-robot motion planning (Gspi) for the disk robots of ``scene``.

    Parameters
    ----------
    scene: the scene (workspace, obstacles, objects, robot radius).
    starts: (N, 2) robot centres now.
    goals: (M, 2) goal centres, M <= N; any robot may take any goal.
    object_poses: (K, 3) current poses of the scene's objects (default: start poses); the
        objects are obstacles. extra_obstacles: more shapes (scene-file dicts).
    time_limit: seconds; on expiry the result is a failure with a reason.
    space: a prebuilt :class:`RobotSpace` to plan in (then ``object_poses`` and
        ``extra_obstacles`` are ignored); its threshold ``r + margin`` is the clearance
        every lattice position keeps.
    seed: tie-breaking seed (the plan is a deterministic function of all arguments).
    lattice_step: lattice spacing L (multiple of the space's 1 cm grid), or a sequence
        of them tried in turn while time is left: after a failure that a finer lattice can
        fix (a goal or start that cannot be linked, a passage narrower than the lattice, a
        stall), the next step is tried. Default (0.05, 0.03, 0.02): GCo's 5 cm first,
        then 3 and 2 cm for passages and pockets the coarser lattices miss (bands of
        free centres narrower than the step); pass a single step for fast failures.
    link_radius: how far a start or goal may be from the lattice nodes it connects to by a
        straight move (default 1.5 L).
    goal_swapping: False gives plain PIBT with a fixed optimal assignment (baseline).
    max_spacing: largest distance between consecutive output rows of a robot.
    goal_tolerance: a goal may have exact clearance down to ``threshold - goal_tolerance``
        (contacts from the manipulation model touch the object and come on a 7.8 mm pixel
        grid; 6 mm is LAMP's ``contact_tolerance``), and two goals may be
        ``2r - goal_tolerance`` apart; the last approach then never gets closer than the
        goal itself (non-worsening rule). Deeper goals raise ValueError.
    start_tolerance: the same for starts (robots left in contact after a push); motions
        out of such a start never reduce the clearance or robot distance further.
    max_steps, stall_steps: step budget, and failure after this many steps without a
        new best summed heuristic (defaults scale with the lattice).
    initial_goal_of: (N,) initial goal per robot (-1 none) instead of the optimal
        assignment (tests and experiments).

    Raises
    ------
    ValueError for malformed arguments: shapes, non-finite values, M > N, starts or goals
    outside the workspace, inside/overlapping obstacles beyond the tolerance, overlapping
    each other. Unreachable or blocked goals are *not* errors: ``success=False``.
    """
    if not _WARM:
        warmup()
    t_begin = time.perf_counter()
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a lamp Scene, got {type(scene).__name__}")
    S = _array2(starts, "starts")
    G = _array2(goals, "goals")
    N, M = len(S), len(G)
    if N < 1:
        raise ValueError("starts must hold at least one robot")
    if M > N:
        raise ValueError(f"goals has {M} points but there are only {N} robots (need M <= N)")
    if not (np.isfinite(time_limit) and time_limit > 0):
        raise ValueError(f"time_limit must be positive, got {time_limit!r}")
    if not (np.isfinite(max_spacing) and max_spacing > 0):
        raise ValueError(f"max_spacing must be positive, got {max_spacing!r}")
    if goal_tolerance < 0 or start_tolerance < 0:
        raise ValueError("goal_tolerance and start_tolerance must be >= 0")
    if space is None:
        space = RobotSpace.from_scene(scene, object_poses, extra_obstacles)
    elif not isinstance(space, RobotSpace):
        raise ValueError(f"space must be a RobotSpace, got {type(space).__name__}")
    c_start = _check_points(space, S, "starts", start_tolerance)
    c_goal = _check_points(space, G, "goals", goal_tolerance)
    goal0: np.ndarray | None = None
    if initial_goal_of is not None:
        goal0 = np.asarray(initial_goal_of, dtype=np.int64).reshape(-1)
        if goal0.shape != (N,) or np.any(goal0 < -1) or np.any(goal0 >= M):
            raise ValueError(f"initial_goal_of must be (N,) goal indices or -1, got {goal0}")
        used = goal0[goal0 >= 0]
        if len(np.unique(used)) != M or len(used) != M:
            raise ValueError("initial_goal_of must give every goal to exactly one robot")

    if M == 0:
        return MRMPPlan(True, S[:, None, :].copy(), np.full(N, -1, np.int64), "", 0,
                        time.perf_counter() - t_begin, {})
    steps = (lattice_step,) if np.isscalar(lattice_step) else tuple(lattice_step)  # type: ignore[arg-type]
    if not steps:
        raise ValueError("lattice_step must be a step or a non-empty sequence of steps")
    deadline = t_begin + float(time_limit)
    stats: dict[str, Any] = {"attempts": []}
    reasons: list[str] = []
    out: _Attempt | None = None
    for L in steps:
        if out is not None and time.perf_counter() >= deadline:
            reasons.append(f"time limit of {time_limit:g} s reached before trying the "
                           f"{L:g} m lattice")
            break
        out = _attempt(space, S, G, c_start, c_goal, float(L), link_radius, goal_swapping,
                       max_spacing, max_steps, stall_steps, goal0, seed, deadline,
                       float(time_limit))
        stats["attempts"].append({"lattice_step": float(L), **out.stats})
        stats.update(out.stats)
        if out.success:
            break
        reasons.append(f"lattice {L:g} m: {out.reason}")
        if not out.retry:
            break
    assert out is not None
    reason = "" if out.success else "; ".join(reasons)
    return MRMPPlan(out.success, out.paths, out.goal_of, reason, out.iterations,
                    time.perf_counter() - t_begin, stats)


@dataclass
class _Attempt:
    success: bool
    reason: str
    paths: np.ndarray
    goal_of: np.ndarray
    iterations: int
    retry: bool  # a finer lattice may succeed (static or stall failure, time left)
    stats: dict[str, Any]


def _attempt(
    space: RobotSpace, S: np.ndarray, G: np.ndarray, c_start: np.ndarray, c_goal: np.ndarray,
    lattice_step: float, link_radius: float | None, goal_swapping: bool, max_spacing: float,
    max_steps: int | None, stall_steps: int | None, goal0: np.ndarray | None, seed: int,
    deadline: float, time_limit: float,
) -> _Attempt:
    """Gspi on one lattice."""
    N, M = len(S), len(G)
    r = space.radius
    thr = space.threshold
    lat: Lattice = get_lattice(space, lattice_step)
    if time.perf_counter() > deadline:
        return _Attempt(False, f"time limit of {time_limit:g} s reached while building the "
                        f"{lattice_step:g} m lattice", S[:, None, :].copy(),
                        np.full(N, -1, np.int64), 0, False, {})
    L = lat.step
    R = 1.5 * L if link_radius is None else float(link_radius)
    V = lat.V
    gv0 = V + N  # first goal vertex
    Vt = V + N + M
    stats: dict[str, Any] = {"lattice_nodes": V}

    def result(success: bool, reason: str, paths: np.ndarray, goal_of: np.ndarray,
               iters: int, retry: bool = False) -> _Attempt:
        return _Attempt(success, reason, paths, goal_of, iters, retry, stats)

    # ---- special vertices and their links ----------------------------------------
    coords = np.concatenate([lat.coords, S, G]).astype(np.float64)
    s_links = lat.links(S, R, np.minimum(thr, c_start))
    g_links = lat.links(G, R, np.minimum(thr, c_goal))
    stats["start_links"] = [len(x[0]) for x in s_links]
    stats["goal_links"] = [len(x[0]) for x in g_links]
    src: list[np.ndarray] = []
    dst: list[np.ndarray] = []
    for i, (nodes, _) in enumerate(s_links):
        src.append(np.full(len(nodes), V + i))
        dst.append(nodes)
    for m, (nodes, _) in enumerate(g_links):
        src.append(np.full(len(nodes), gv0 + m))
        dst.append(nodes)
        src.append(nodes)
        dst.append(np.full(len(nodes), gv0 + m))
    # direct start -> goal moves for robots already close to a goal
    dSG = np.hypot(S[:, None, 0] - G[None, :, 0], S[:, None, 1] - G[None, :, 1])
    si, gi = np.nonzero(dSG <= R)
    direct = np.zeros((N, M), dtype=bool)
    if len(si):
        clr = space.segment_clearance(S[si], G[gi])
        ok = clr >= np.minimum(thr, np.minimum(c_start[si], c_goal[gi])) - 1e-12
        si, gi = si[ok], gi[ok]
        direct[si, gi] = True
        src.append(V + si)
        dst.append(gv0 + gi)
    src_a = np.concatenate(src).astype(np.int64)
    dst_a = np.concatenate(dst).astype(np.int64)
    order = np.argsort(src_a, kind="stable")
    src_a, dst_a = src_a[order], dst_a[order]
    xptr = np.zeros(Vt + 1, dtype=np.int64)
    np.add.at(xptr, src_a + 1, 1)
    xptr = np.cumsum(xptr)
    xidx = np.ascontiguousarray(dst_a)
    max_extra = int(np.max(np.diff(xptr)))
    maxc = 9 + max_extra

    # ---- heuristic: lazy Dijkstra per goal, seeded with the goal's links ------------
    # + _EPS on every vertex but the goal itself: a lattice node (or start) that coincides
    # with the goal must not tie with the goal vertex (a robot would wander off by 0 m)
    hs = (
        np.full((M, V), np.inf), np.full((M, V), -1, dtype=np.int64),
        np.empty((M, V), dtype=np.int64), np.zeros(M, dtype=np.int64),
        np.zeros((M, N + M), dtype=np.bool_), np.zeros((M, N + M)),
    )
    for m, (nodes, lens) in enumerate(g_links):
        _seed_goal(m, nodes.astype(np.int64), lens + _EPS, hs)
    gr = (coords, lat.nbr, lat.dlen, xptr, xidx)

    # ---- initial assignment (optimal, on heuristic distances) ---------------------
    C = np.empty((N, M))
    for m in range(M):  # one goal at a time, so that the time limit is kept
        C[:, m] = _start_costs(gr, V, gv0, hs, N, m)
        if time.perf_counter() > deadline:
            return result(False, f"time limit of {time_limit:g} s reached while computing "
                          "heuristic distances", S[:, None, :].copy(),
                          np.full(N, -1, np.int64), 0)
    reach_goal = np.isfinite(C).any(axis=0)
    if not reach_goal.all():
        bad = np.nonzero(~reach_goal)[0].tolist()
        why = [
            f"goal {m} at {G[m].round(3).tolist()}"
            + (" cannot be connected to the lattice" if len(g_links[m][0]) == 0 and
               not direct[:, m].any() else " is unreachable from every start")
            for m in bad
        ]
        return result(False, "; ".join(why), S[:, None, :].copy(), np.full(N, -1, np.int64), 0,
                      retry=True)
    if goal0 is None:
        rows, cols = linear_sum_assignment(np.where(np.isfinite(C), C, _BIG))
        if np.any(~np.isfinite(C[rows, cols])):
            return result(False, "no assignment of robots to goals reaches every goal "
                          "(some goals are reachable only by the same robots)",
                          S[:, None, :].copy(), np.full(N, -1, np.int64), 0, retry=True)
        goal = np.full(N, -1, dtype=np.int64)
        goal[rows] = cols
    else:
        goal = goal0.copy()

    # initial priorities: farther robots first (PIBT's eps_i), ties by seeded noise
    rng = np.random.default_rng(seed)
    h0 = np.array([C[i, goal[i]] if goal[i] >= 0 else 0.0 for i in range(N)])
    h0 = np.where(np.isfinite(h0), h0, 1e3)
    prio = 0.5 * h0 / (h0.max() + 1.0) + 0.4 * rng.random(N) / (N + 1) + 0.05
    prio = np.where(goal >= 0, prio, 0.01 * rng.random(N))

    # ---- Gspi steps -------------------------------------------------------------
    if max_steps is None:
        max_steps = int(20 * (lat.ids.shape[0] + lat.ids.shape[1]) + 50 * N)
    if stall_steps is None:
        stall_steps = int(2 * (lat.ids.shape[0] + lat.ids.shape[1]) + 10 * N)
    cur = np.arange(V, V + N, dtype=np.int64)
    hist = np.empty((max_steps + 1, N), dtype=np.int64)
    hist[0] = cur
    hsum = np.zeros(max_steps + 1)
    best_h = np.inf
    best_t = 0
    t = 0
    done = False
    reason = ""
    retry = False
    chunk = 16
    seed_i = int(seed) & 0x7FFFFFFF
    t_chunk = time.perf_counter()
    t_prev = 0
    while True:
        t_chunk = time.perf_counter()
        t_prev = t
        t1 = min(t + chunk, max_steps)
        t_new, done = _run_steps(gr, V, gv0, hs, cur, goal, prio, 2.0 * r, seed_i,
                                 goal_swapping, hist, hsum, t, t1, maxc)
        for k in range(t + 1, t_new + 1):
            if hsum[k] < best_h - 1e-9:
                best_h = hsum[k]
                best_t = k
        t = t_new
        if done:
            break
        if t >= max_steps:
            reason = f"step budget of {max_steps} Gspi steps exhausted"
            retry = True
            break
        if t - best_t > stall_steps:
            reason = f"no progress for {stall_steps} steps (deadlock or livelock)"
            retry = True
            break
        now = time.perf_counter()
        if now > deadline:
            reason = f"time limit of {time_limit:g} s reached after {t} steps"
            break
        # next chunk: at most ~20 ms of work, so the time limit is kept closely
        per_step = (now - t_chunk) / max(1, t - t_prev)
        chunk = int(max(1, min(256, 2 * chunk, 0.02 / max(per_step, 1e-7),
                               (deadline - now) / max(per_step, 1e-7) + 1)))

    # ---- output: drop all-wait steps, densify --------------------------------------
    P = coords[hist[: t + 1]]  # (t+1, N, 2)
    moved = np.any(np.any(P[1:] != P[:-1], axis=2), axis=1)
    keep = np.concatenate([[True], moved])
    P = P[keep]
    stats["steps_removed"] = int((~moved).sum())
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
    paths = np.ascontiguousarray(P.transpose(1, 0, 2))
    goal_of = goal.copy()
    if done:
        # independent of the search's bookkeeping: every goal held by exactly one robot
        final_ok = np.all(np.hypot(*(paths[goal_of >= 0, -1] - G[goal_of[goal_of >= 0]]).T)
                          <= 1e-9)
        counts = np.bincount(goal_of[goal_of >= 0], minlength=M)
        if final_ok and np.all(counts == 1):
            return result(True, "", paths, goal_of, t)
        reason = "internal error: final positions do not match the goals"  # pragma: no cover
    return result(False, reason, paths, goal_of, t, retry)
