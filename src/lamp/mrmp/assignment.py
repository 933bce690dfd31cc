"""Gspi's initial assignment of robots to goals: bottleneck first, then sum (as TSWAP).

``bottleneck`` (default): among the assignments that give every goal a robot, those whose
longest heuristic distance is smallest (the *bottleneck* ``B*``), and among them one of
least summed distance. ``sum``: least summed distance over all assignments (the
Hungarian method on the whole cost matrix; the objective Gspi used before).

Distances are exact lattice distances (:mod:`lamp.mrmp.goal_distances`) and are computed
lazily: the straight-line distance is a lower bound, so only pairs closer than a growing
bound ``B`` are evaluated, each goal's search expanding to ``B`` and no further. ``B``
starts just above the straight-line bottleneck (found to within 1/256 by matching the
straight-line pairs; no lattice bound below it can do) and grows by a tenth until the
pairs below it admit a perfect matching (Kuhn's augmenting paths,
compiled, each round growing the last round's matching); ``B*`` is then found by
bisection over the distances below ``B``, each trial growing the matching of the pairs
below the previous bound, and the sum is minimised over the pairs within ``B*``
(``scipy.optimize.linear_sum_assignment``; for fleets of :data:`~lamp.mrmp.
gspi_kernels.ALL_PAIRS_BELOW` robots or more, over those pairs only,
:mod:`lamp.mrmp.sparse_lsa`, ties broken by :data:`TIE`). On a 9.6 m map with 400
robots each goal's search stops about 1.5 m out instead of covering the map.

Large fleets (``coarse`` given, the goals times the lattice nodes within the straight-line
bottleneck above :data:`COARSE_NODES`): the same procedure over the distances of the
lattice's block graph (:mod:`lamp.mrmp.coarse`), then each chosen pair's exact lattice
distance as its cost; the exact procedure when the block graph finds no assignment or a
chosen pair has no lattice path.

Guarantee (tested against brute force over all permutations on small instances, and
for fleets against the whole cost matrix): the returned assignment reaches every goal,
its longest distance is the least possible, and its sum is the least among assignments
with that longest distance (for fleets to within :data:`TIE` times the summed squares). Over the block graph
(tested with the coarse way forced): every goal has one robot, the costs are the exact
lattice distances and ``bound`` their largest, which is at least the exact ``B*``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numba as nb
import numpy as np
from scipy.optimize import linear_sum_assignment

from lamp.mrmp.bottleneck import least_threshold, straight_line_bottleneck
from lamp.mrmp.coarse import CoarseGraph, coarse_below
from lamp.mrmp.goal_distances import GoalDistances, hval, hval_pairs, start_costs
from lamp.mrmp.gspi_kernels import ALL_PAIRS_BELOW, Graph
from lamp.mrmp.heuristic_reads import hval_below
from lamp.mrmp.near_pairs import NearPairs
from lamp.mrmp.sparse_lsa import sparse_assignment

__all__ = ["ASSIGNMENTS", "Assignment", "assign", "straight_line_bottleneck", "unreached_reason"]

#: The objectives of the initial assignment (``plan_paths(assignment=...)``).
ASSIGNMENTS = ("bottleneck", "sum")
#: Finite stand-in for an infinite cost in the dense (``sum``) assignment problem.
_BIG = 1e9
#: Up to this many robot-goal pairs every distance is computed at once (as the
#: ``sum`` objective does): fewer calls into compiled code than the growing bound needs.
DENSE_PAIRS = 64
#: Fleets whose exact searches would settle more nodes than this (the goals times the
#: lattice nodes within the straight-line bottleneck) are assigned over the coarse graph.
COARSE_NODES = 1e7
#: Fleets' least sum over the pairs within ``B*`` breaks ties by the summed squares:
#: each cost ``c`` counts as ``c + TIE * c**2`` (among equal sums, the one with the
#: shorter longest ways; the sum is least to within ``TIE`` times the summed squares).
TIE = 1e-6
#: Growth factor of the bound ``B`` between rounds (from the straight-line floor; each
#: round evaluates the pairs not yet known to be below the bound).
_GROWTH = 1.1
#: Fleets' rounds (:func:`_least_bottleneck`'s ``schedule``): the bound grows by 5 % a
#: round, the first search reaches four rounds ahead (1.24 times the straight-line floor),
#: later ones none, and each goal's window has room for 1.2 times a search's reach, so
#: that later rounds resume it in place (growing a window copies all of it).
FLEET_ROUNDS = (1.05, 4, 0, 1.2)


@dataclass(frozen=True)
class Assignment:
    """``goal[i]``: robot i's goal (-1 none), ``cost[i]``: its heuristic distance (0
    without a goal), ``why``: the reason when no assignment reaches every goal (then
    ``goal`` is None), ``timed_out``: the deadline passed first; ``bound``: ``B*``;
    ``floor``: a lower bound on the straight-line bottleneck (fleets; else 0)."""

    goal: np.ndarray | None
    cost: np.ndarray
    why: str = ""
    timed_out: bool = False
    bound: float = 0.0
    floor: float = 0.0


@nb.njit(cache=True)
def _grow_matching(ptr: np.ndarray, idx: np.ndarray, val: np.ndarray, t: float,
                   mg: np.ndarray, mr: np.ndarray) -> int:
    """Grow the matching ``mg`` (goal -> robot, -1 none) / ``mr`` (robot -> goal) to a
    maximum one of the pairs ``(m, idx[k])``, ``ptr[m] <= k < ptr[m + 1]``, with
    ``val[k] <= t`` (Kuhn's augmenting paths, iterative, passes until none is found; the
    given matching must use such pairs only). Returns its size."""
    M = ptr.shape[0] - 1
    seen = np.zeros(mr.shape[0], np.int64)
    stk_g = np.empty(M + 1, np.int64)
    stk_e = np.empty(M + 1, np.int64)
    stamp = 0
    grown = True
    while grown:
        grown = False
        stamp += 1
        for g0 in range(M):
            if mg[g0] >= 0:
                continue
            sp = 0
            stk_g[0] = g0
            stk_e[0] = ptr[g0]
            while sp >= 0:
                g = stk_g[sp]
                e = stk_e[sp]
                if e == ptr[g + 1]:
                    sp -= 1
                    continue
                stk_e[sp] = e + 1
                r = idx[e]
                if val[e] > t or seen[r] == stamp:
                    continue
                seen[r] = stamp
                if mr[r] < 0:  # augment along the stack
                    for q in range(sp, -1, -1):
                        rr = idx[stk_e[q] - 1]
                        mg[stk_g[q]] = rr
                        mr[rr] = stk_g[q]
                    grown = True
                    break
                sp += 1
                stk_g[sp] = mr[r]
                stk_e[sp] = ptr[mr[r]]
    n = 0
    for g in range(M):
        n += mg[g] >= 0
    return n


def unreached_reason(G: np.ndarray, no_link: np.ndarray, unreachable: np.ndarray) -> str:
    """Why the goals of ``no_link`` (no link to the lattice or a start) and
    ``unreachable`` (reachable from no start) cannot be reached, goal by goal."""
    why = [f"goal {m} at {G[m].round(3).tolist()}"
           + (" cannot be connected to the lattice" if no_link[m]
              else " is unreachable from every start")
           for m in np.nonzero(no_link | unreachable)[0].tolist()]
    return "; ".join(why)


def assign(gr: Graph, V: int, hs: GoalDistances, S: np.ndarray, G: np.ndarray,
           no_link: np.ndarray, objective: str, goal0: np.ndarray | None,
           deadline: float, coarse: CoarseGraph | None = None) -> Assignment:
    """The initial goal of each robot (see the module docstring); ``no_link[m]``: goal m
    has no link to the lattice or to a start; ``goal0``: a given assignment (checked for
    reachability only); ``coarse``: the lattice's block graph, for the bottleneck objective
    over the coarse distances (fleets)."""
    N, M = len(S), len(G)
    gv0 = V + N
    none = np.zeros(N)
    if no_link.any():
        return Assignment(None, none, unreached_reason(G, no_link, np.zeros(M, bool)))
    if goal0 is not None:
        cost = np.array([hval(int(g), V + i, gr, V, gv0, hs) if g >= 0 else 0.0
                         for i, g in enumerate(goal0.tolist())])
        bad = [m for m in range(M) if not np.isfinite(cost[goal0 == m]).all()]
        if bad:
            return Assignment(None, none, f"goal {bad[0]} at {G[bad[0]].round(3).tolist()} "
                              "is unreachable from the robot given for it")
        return Assignment(goal0.copy(), cost)
    if objective == "sum" or N * M <= DENSE_PAIRS:
        return _dense(gr, V, hs, S, G, deadline, objective == "bottleneck")
    E = NearPairs(S, G)  # the straight lines, found within a bound as needed
    floor = _straight_floor(E)
    if coarse is not None and M * np.pi * floor**2 / hs.step**2 > COARSE_NODES:
        got = _coarse_bottleneck(gr, V, hs, S, G, E, floor, coarse, deadline)
        if got is not None:
            return replace(got, floor=floor)
    return replace(_bottleneck(gr, V, hs, S, G, E, floor, deadline), floor=floor)


def _costs(gr: Graph, V: int, hs: GoalDistances, N: int, M: int,
           deadline: float) -> np.ndarray | None:
    """The (N, M) exact distances of every start to every goal (None past the deadline);
    in one compiled call for small problems, else goal by goal to keep the deadline."""
    if N * M <= DENSE_PAIRS:
        return start_costs(0, M, N, gr, V, hs)
    C = np.empty((N, M))
    for m in range(M):
        C[:, m] = start_costs(m, m + 1, N, gr, V, hs)[:, 0]
        if time.perf_counter() > deadline:
            return None
    return C


def _dense(gr: Graph, V: int, hs: GoalDistances, S: np.ndarray, G: np.ndarray,
           deadline: float, bottleneck: bool) -> Assignment:
    """The assignment on the whole cost matrix: least sum, after the least bottleneck when
    ``bottleneck`` (small problems, and the ``sum`` objective)."""
    N, M = len(S), len(G)
    C = _costs(gr, V, hs, N, M, deadline)
    if C is None:
        return Assignment(None, np.zeros(N), timed_out=True)
    reach = np.isfinite(C).any(axis=0)
    if not reach.all():
        return Assignment(None, np.zeros(N), unreached_reason(G, np.zeros(M, bool), ~reach))
    if bottleneck:
        # every goal needs a robot: B* >= the largest of the goals' nearest distances; a
        # least-sum assignment that meets this bound is bottleneck-optimal as it is
        floor = C.min(axis=0).max()
        rows, cols = linear_sum_assignment(np.where(np.isfinite(C), C, _BIG))
        if C[rows, cols].max() <= floor:
            return _chosen(C, rows, cols)
    vals = np.unique(C[np.isfinite(C)])
    a = least_threshold(C, vals, 0 if bottleneck else len(vals) - 1, len(vals) - 1)
    W = np.where(vals[a] >= C, C, _BIG)
    rows, cols = linear_sum_assignment(W)
    if np.any(W[rows, cols] >= _BIG):
        return Assignment(None, np.zeros(N), "no assignment of robots to goals reaches every "
                          "goal (some goals are reachable only by the same robots)")
    return _chosen(C, rows, cols)


def _chosen(C: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> Assignment:
    """The assignment of robots ``rows`` to goals ``cols`` with costs from ``C`` (N, M)."""
    goal = np.full(len(C), -1, dtype=np.int64)
    goal[rows] = cols
    cost = np.zeros(len(C))
    cost[rows] = C[rows, cols]
    return Assignment(goal, cost, bound=float(C[rows, cols].max()))


def _straight_floor(E: NearPairs) -> float:
    """A lower bound on the straight-line bottleneck of the goal-robot distances ``E``:
    the largest threshold found (by doubling, then bisection) at which the pairs no longer
    than it match no more than ``M - 1`` goals; 0 when even the least one matches all."""
    M = E.M
    t = E.nearest()  # every goal needs a robot
    empty = np.full(E.N, -1, np.int64)
    cap = 2.0 * t
    while True:
        pm, pi, val = E.within(cap, strict=False)
        ptr = np.searchsorted(pm, np.arange(M + 1))
        if _grow_matching(ptr, pi, val, cap, np.full(M, -1, np.int64), empty.copy()) == M:
            break
        t, cap = cap, 2.0 * cap
    base_g, base_r = np.full(M, -1, np.int64), empty.copy()
    if _grow_matching(ptr, pi, val, t, base_g, base_r) == M:
        return 0.0
    lo, hi = t, cap
    # each trial grows a maximum matching of the pairs within lo (one of them is one
    # within mid): the same decisions as from an empty matching, in less work
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        mg, mr = base_g.copy(), base_r.copy()
        if _grow_matching(ptr, pi, val, mid, mg, mr) == M:
            hi = mid
        else:
            lo, base_g, base_r = mid, mg, mr
    return lo


def _bottleneck(gr: Graph, V: int, hs: GoalDistances, S: np.ndarray, G: np.ndarray,
                E: NearPairs, floor: float, deadline: float) -> Assignment:
    """Bottleneck, then sum, over the exact lattice distances."""
    N, M = len(S), len(G)

    def below(pm: np.ndarray, pi: np.ndarray, bound: float, room: float) -> np.ndarray:
        return hval_below(pm, V + pi, bound, gr, V, V + N, hs, room)

    def exhausted(has_pair: np.ndarray, bound: float, settled: bool) -> Assignment | None:
        # searches that are complete (whole lattice, queue empty) know all they can reach
        complete = np.isinf(hs.rad) & (hs.bcnt.sum(axis=1) == 0)
        if (complete & ~has_pair).any():
            return Assignment(None, np.zeros(N), unreached_reason(G, np.zeros(M, bool),
                                                            complete & ~has_pair))
        if complete.all() and settled:
            return Assignment(None, np.zeros(N), "no assignment of robots to goals reaches "
                              "every goal (some goals are reachable only by the same robots)")
        return None

    # fleets: the first search, while each window is in cache, reaches the bound of a
    # few rounds later; later ones, resumed with the windows out of cache, go no further
    # than needed (smaller teams keep the searches they were tested bit for bit with)
    rounds = FLEET_ROUNDS if N >= ALL_PAIRS_BELOW else (_GROWTH, 0, 0, 1.0)
    return _least_bottleneck(E, floor, below, exhausted, deadline, 4.0 * hs.step, rounds)


def _coarse_bottleneck(gr: Graph, V: int, hs: GoalDistances, S: np.ndarray,
                       G: np.ndarray, E: NearPairs, floor: float, cg: CoarseGraph,
                       deadline: float) -> Assignment | None:
    """Bottleneck, then sum, over the coarse distances (:mod:`lamp.mrmp.coarse`); each
    chosen pair's cost then its exact lattice distance. None when the coarse graph finds
    no assignment or a chosen pair has no lattice path (the caller then solves exactly);
    past the deadline, the timed-out result."""
    N, M = len(S), len(G)
    xptr, xidx = gr[3], gr[4]

    def block_of(v: int) -> int:
        for n in xidx[xptr[v]:xptr[v + 1]].tolist():
            if n < V:
                return int(cg.block[n])
        return -1

    sblk = np.array([block_of(V + i) for i in range(N)], dtype=np.int64)
    gblk = np.array([block_of(V + N + m) for m in range(M)], dtype=np.int64)
    far = 3.0 * float(np.hypot(*(np.vstack([S, G]).max(axis=0)
                                 - np.vstack([S, G]).min(axis=0)))) + 1.0

    def below(pm: np.ndarray, pi: np.ndarray, bound: float, room: float) -> np.ndarray:
        return coarse_below(pm, pi, bound, sblk, gblk, S, G, cg.rep, cg.nbr, cg.wlen,
                            cg.unit)

    def exhausted(has_pair: np.ndarray, bound: float, settled: bool) -> Assignment | None:
        return Assignment(None, np.zeros(N)) if bound > far else None

    # block searches start again each time: each reaches the bound of three rounds later
    got = _least_bottleneck(E, floor, below, exhausted, deadline, 4.0 * hs.step,
                            (_GROWTH, 3, 3, 1.0))
    if got.timed_out:
        return got
    if got.goal is None:
        return None
    held = np.nonzero(got.goal >= 0)[0]
    held = held[np.argsort(got.goal[held], kind="stable")]
    cost = np.zeros(N)
    cost[held] = hval_pairs(got.goal[held], V + held, gr, V, V + N, hs)
    if not np.isfinite(cost).all():
        return None
    return Assignment(got.goal, cost, bound=float(cost.max()))


def _least_bottleneck(E: NearPairs, floor: float, below: Callable, exhausted: Callable,
                      deadline: float, least: float,
                      schedule: tuple[float, int, int, float]) -> Assignment:
    """Bottleneck, then sum, over the distances ``below(pm, pi, bound, room)`` gives for
    pairs (goal ``pm[k]``, robot ``pi[k]``) (inf at or above ``bound``; never below the
    straight line; ``room``: how far a goal's search may later be resumed in place);
    ``exhausted(has_pair, bound, settled)``: an Assignment that ends the search when no
    larger bound can give a perfect matching, else None (``has_pair``: the goals with a
    finite distance known, ``settled``: every pair's distance known and below the
    bound); ``E``: the straight lines, ``floor``:
    :func:`_straight_floor` of them. ``schedule = (growth, ahead, ahead_later, room)``:
    the bound grows by ``growth`` a round; the first search reaches the bound of the
    round ``ahead`` rounds later (each later one ``ahead_later``), so that the rounds up
    to there need none, with room for ``room`` times that. The result does not depend on
    the schedule: ``B*`` is found among the exact distances below the first bound that
    admits a perfect matching, and the sum is taken over all pairs within it."""
    M, N = E.M, E.N
    growth, ahead, ahead_later, room = schedule
    # distances are at least the straight lines: no bound below theirs can do
    bound = max(floor * 1.02, least)
    lo = 0.0  # no perfect matching among the pairs with distance < lo
    mg = np.full(M, -1, dtype=np.int64)  # a maximum matching of the pairs below the bound
    mr = np.full(N, -1, dtype=np.int64)
    # the pairs whose straight line is below the last bound (goal * N + robot, ascending)
    # and their distances (exact where below that bound, else inf)
    keys, known = np.zeros(0, np.int64), np.zeros(0)
    searched = 0.0  # the pairs' distances are exact below it (inf: not below it)
    while True:
        if bound > searched:
            rounds = ahead if searched == 0.0 else ahead_later
            searched = bound
            for _ in range(rounds):  # as the bound will grow, to the same float
                searched *= growth
            gm, gi, _ = E.within(searched, strict=True)
            fresh = np.full(len(gm), np.inf)
            fresh[np.searchsorted(gm * N + gi, keys)] = known  # the bound only grows
            keys, known = gm * N + gi, fresh
            todo = np.flatnonzero(np.isinf(known))  # grouped by goal
            known[todo] = below(gm[todo], gi[todo], searched, room * searched)
        ok = np.flatnonzero(bound > known)
        pm, pi, c = gm[ok], gi[ok], known[ok]
        ptr = np.searchsorted(pm, np.arange(M + 1))
        # pairs are only added as the bound grows: the last matching is still one
        if _grow_matching(ptr, pi, c, np.inf, mg, mr) == M:
            break
        if time.perf_counter() > deadline:
            return Assignment(None, np.zeros(N), timed_out=True)
        # goals some robot reaches, as far as known (a search may reach past the bound)
        has_pair = np.zeros(M, bool)
        fin = np.isfinite(known)
        has_pair[gm[fin]] = True
        # every pair known and within the bound: a larger one adds none
        settled = len(keys) == M * N and bool((bound > known[fin]).all())
        end = exhausted(has_pair, bound, settled)
        if end is not None:
            return end
        lo = bound
        base_g, base_r = mg.copy(), mr.copy()
        bound *= growth
    return _least_sum_within(M, N, ptr, pm, pi, c, lo, base_g if lo > 0.0 else None,
                             base_r if lo > 0.0 else None)


def _least_sum_within(M: int, N: int, ptr: np.ndarray, pm: np.ndarray, pi: np.ndarray,
                      c: np.ndarray, lo: float, base_g: np.ndarray | None,
                      base_r: np.ndarray | None) -> Assignment:
    """B* (the least distance d such that the pairs with distance <= d match every goal;
    each trial grows the matching ``base`` of the pairs below ``lo``, maximum there), then
    the least sum over the pairs within B*."""
    vals = np.unique(c[c >= lo])
    a, b = 0, len(vals) - 1
    while a < b:
        mid = (a + b) // 2
        if base_g is not None:
            tg, tr = base_g.copy(), base_r.copy()
        else:  # first round: no base matching
            tg, tr = np.full(M, -1, np.int64), np.full(N, -1, np.int64)
        if _grow_matching(ptr, pi, c, vals[mid], tg, tr) == M:
            b = mid
        else:
            a = mid + 1
    best = float(vals[a])
    keep = c <= best
    if N >= ALL_PAIRS_BELOW:  # fleets: over the pairs within B* only (sparse_lsa)
        kg, ki, kc = pm[keep], pi[keep], c[keep]
        got = sparse_assignment(np.searchsorted(kg, np.arange(M + 1)), ki, kc + TIE * kc**2,
                                N)
        if got is not None:
            chosen = np.flatnonzero(ki == got[kg])  # one pair per goal
            goal = np.full(N, -1, dtype=np.int64)
            goal[ki[chosen]] = kg[chosen]
            cost = np.zeros(N)
            cost[ki[chosen]] = kc[chosen]
            return Assignment(goal, cost, bound=best)
    # least sum over the pairs within B* (a perfect matching exists among them, so the
    # stand-in cost of the other pairs is never chosen); the dense solver is faster here
    # than the sparse one, whose augmenting paths crawl on such tight graphs
    W = np.full((M, N), _BIG)
    W[pm[keep], pi[keep]] = c[keep]
    rows, cols = linear_sum_assignment(W)
    goal = np.full(N, -1, dtype=np.int64)
    goal[cols] = rows
    cost = np.zeros(N)
    cost[cols] = W[rows, cols]
    return Assignment(goal, cost, bound=best)
