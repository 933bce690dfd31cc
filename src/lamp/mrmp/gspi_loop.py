"""Gspi's step loop (:func:`run_search`: PIBT steps with goal swaps in compiled chunks,
:mod:`lamp.mrmp.gspi_kernels`) and, for fleets, its restarts after a stall.

A fleet of more than :data:`~lamp.mrmp.effort.STALL_ABOVE` robots whose steps stall
(no new least summed heuristic for :func:`~lamp.mrmp.effort.stall_limit` steps: robots
that block each other's goals for good, as four robots in a dead-end corridor of four
goals that entered it in the wrong order) starts the steps again on the same lattice
from the same assignment, with other tie-breaking seeds (:data:`RESTARTS` of them,
:func:`restart_seed`), before a finer lattice is tried: the steps' priorities and ties
decide which robot enters such a corridor first. Only stalled searches restart, so the
plans of searches that do not stall are the same as without restarts.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from lamp.mrmp.effort import STALL_ABOVE
from lamp.mrmp.goal_distances import GoalDistances
from lamp.mrmp.gspi_kernels import ALL_PAIRS_BELOW, Graph, run_steps
from lamp.mrmp.links import Links
from lamp.mrmp.result import GspiStatus

__all__ = ["RESTARTS", "Search", "SearchOptions", "priorities", "restart_seed",
           "run_search", "search_with_restarts"]

#: Restarts of a fleet's stalled steps on the same lattice, each with its own seed.
RESTARTS = 4


@dataclass(frozen=True)
class SearchOptions:
    """The search settings of :func:`plan_paths` that every lattice attempt shares."""

    link_radius: float | None
    goal_swapping: bool
    max_spacing: float
    max_steps: int | None
    stall_steps: int | None
    seed: int
    deadline: float  # time.perf_counter() seconds
    time_limit: float  # for messages
    assignment: str
    swap_radius: float | None


def priorities(cost: np.ndarray, goal: np.ndarray, seed: int) -> np.ndarray:
    """Initial priorities: farther robots first (PIBT's eps_i), ties by seeded noise;
    robots without a goal last."""
    N = len(goal)
    rng = np.random.default_rng(seed)
    h0 = np.where(goal >= 0, cost, 0.0)
    h0 = np.where(np.isfinite(h0), h0, 1e3)
    prio = 0.5 * h0 / (h0.max() + 1.0) + 0.4 * rng.random(N) / (N + 1) + 0.05
    return np.where(goal >= 0, prio, 0.01 * rng.random(N))


@dataclass
class Search:
    """Gspi's step loop state: ``hist[k]`` the vertices after step k (``hist[0]`` the
    starts), ``t`` steps taken, ``done`` when every goal is held."""

    hist: np.ndarray
    t: int = 0
    done: bool = False
    reason: str = ""
    retry: bool = False
    status: GspiStatus = GspiStatus.SOLVED


def run_search(graph: Graph, V: int, gv0: int, hs: GoalDistances, goal: np.ndarray,
               prio: np.ndarray, two_r: float, links: Links, max_steps: int,
               stall_steps: int, opts: SearchOptions) -> Search:
    """Gspi steps in compiled chunks until every goal is held, the step budget is spent,
    the summed heuristic stalls for ``stall_steps`` or the deadline passes."""
    N = len(goal)
    cur = np.arange(V, V + N, dtype=np.int64)
    cap = min(max_steps, 512) + 1  # history rows, doubled as needed
    out = Search(np.empty((cap, N), dtype=np.int64))
    out.hist[0] = cur
    hsum = np.zeros(cap)
    near = two_r + 2.0 * links.max_move + 1e-9
    stuck = np.zeros((2, N), dtype=np.int64)  # deadlock detection (gspi_kernels.run_steps)
    besth = np.full(N, np.inf)
    swap_r = 2.0 * near if opts.swap_radius is None else float(opts.swap_radius)
    best_h = np.inf
    best_t = 0
    # steps per compiled call, adapted to the clock; a call costs about 0.05 ms before it
    # starts (Numba types its arguments on every call: goal_distances._typeof_goal_distances)
    chunk = max(1, min(64, 8192 // N))
    seed_i = int(opts.seed) & 0x7FFFFFFF
    while True:
        t_chunk = time.perf_counter()
        t_prev = out.t
        # never past the step where a stall would be declared: where the search stops
        # then depends on the steps alone, not on how the clock cut them into chunks
        t1 = min(out.t + chunk, max_steps, best_t + stall_steps + 1)
        if t1 + 1 > len(hsum):
            cap = min(max_steps + 1, max(2 * len(hsum), t1 + 1))
            out.hist = np.concatenate([out.hist, np.empty((cap - len(hsum), N), np.int64)])
            hsum = np.concatenate([hsum, np.zeros(cap - len(hsum))])
        t_new, out.done = run_steps(graph, V, gv0, hs, cur, goal, prio, two_r, seed_i,
                                    opts.goal_swapping, out.hist, hsum, out.t, t1,
                                    links.max_candidates, near, swap_r, stuck, besth,
                                    N >= ALL_PAIRS_BELOW)
        for k in range(out.t + 1, t_new + 1):
            if hsum[k] < best_h - 1e-9:
                best_h = hsum[k]
                best_t = k
        out.t = t_new
        if out.done:
            return out
        if out.t >= max_steps:
            out.reason, out.retry = f"step budget of {max_steps} Gspi steps exhausted", True
            out.status = GspiStatus.STEP_BUDGET
            return out
        if out.t - best_t > stall_steps:
            out.reason = f"no progress for {stall_steps} steps (deadlock or livelock)"
            out.retry, out.status = True, GspiStatus.STALLED
            return out
        now = time.perf_counter()
        if now > opts.deadline:
            out.reason = f"time limit of {opts.time_limit:g} s reached after {out.t} steps"
            out.status = GspiStatus.TIME_LIMIT
            return out
        # next chunk: at most ~20 ms of work, so the time limit is kept closely
        per_step = (now - t_chunk) / max(1, out.t - t_prev)
        chunk = int(max(1, min(256, 2 * chunk, 0.02 / max(per_step, 1e-7),
                               (opts.deadline - now) / max(per_step, 1e-7) + 1)))


def restart_seed(seed: int, k: int) -> int:
    """The tie-breaking seed of restart ``k`` (1, 2, ...) of a search seeded ``seed``."""
    return (int(seed) + 1_000_003 * k) & 0x7FFFFFFF


def search_with_restarts(graph: Graph, V: int, gv0: int, hs: GoalDistances,
                         goal: np.ndarray, cost: np.ndarray, two_r: float, links: Links,
                         max_steps: int, stall_steps: int, opts: SearchOptions
                         ) -> tuple[Search, np.ndarray, int]:
    """:func:`run_search` from the assignment ``goal`` (robot -> goal, -1 none; its
    heuristic distances ``cost``) with :func:`priorities` of ``opts.seed``; for fleets
    of more than :data:`~lamp.mrmp.effort.STALL_ABOVE` robots, after a stall, again from
    the same assignment with :func:`restart_seed` ``k = 1 .. RESTARTS`` while stalls
    go on and the deadline allows. Returns the last search, its robots' goals (the
    steps swap them) and the restarts made; a stall the restarts did not end keeps the
    first stall's reason."""
    restarts = RESTARTS if len(goal) > STALL_ABOVE else 0
    seed, first = opts.seed, None
    for k in range(restarts + 1):
        if k:
            seed = restart_seed(opts.seed, k)
        run_goal = goal.copy()
        run = run_search(graph, V, gv0, hs, run_goal, priorities(cost, goal, seed), two_r,
                         links, max_steps, stall_steps,
                         opts if k == 0 else replace(opts, seed=seed))
        first = first or run
        if run.status != GspiStatus.STALLED or time.perf_counter() > opts.deadline:
            break
    if run.status == GspiStatus.STALLED:
        run.reason = first.reason + (f" ({k} restarts with other seeds stalled too)"
                                     if k else "")
    return run, run_goal, k
