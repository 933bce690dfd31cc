"""Weighted A* over the :class:`lamp.search.dstar_lite.Graph` protocol.

Used by the GCo baselines (object-only weighted A*, w = 2; see ``gco_lattice.py``). With
``weight = 1`` and a consistent heuristic it returns a shortest path; with ``weight = w > 1``
it expands each vertex at most once (no re-opening) and, for a consistent heuristic, the
returned cost is still at most ``w`` times the optimum (Likhachev et al., ARA*, 2003).
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field

from lamp.search.graph import Graph, SearchStatus

INF = math.inf


@dataclass
class AStarResult:
    """Outcome of one search: ``path`` is ``[start, ..., goal]`` (empty unless SUCCESS)."""

    status: SearchStatus
    path: list[Hashable] = field(default_factory=list)
    cost: float = INF
    expansions: int = 0
    time_s: float = 0.0

    @property
    def success(self) -> bool:
        return self.status is SearchStatus.SUCCESS


def weighted_astar(
    graph: Graph,
    start: Hashable,
    goal: Hashable | None = None,
    *,
    weight: float = 1.0,
    is_goal: Callable[[Hashable], bool] | None = None,
    heuristic: Callable[[Hashable], float] | None = None,
    max_expansions: int | None = None,
    time_limit: float | None = None,
) -> AStarResult:
    """Weighted A* from ``start`` to ``goal`` (or to any vertex with ``is_goal(v)``).

    Priorities are ``g + weight * h`` with ``h = heuristic(v)`` (default
    ``graph.heuristic(v, goal)``). Ties are broken towards larger g (deeper vertices), then
    by insertion order, so results are deterministic.
    """
    if not (weight >= 1.0 and math.isfinite(weight)):
        raise ValueError(f"weight must be finite and >= 1, got {weight!r}")
    if goal is None and is_goal is None:
        raise ValueError("give a goal vertex or an is_goal predicate")
    if heuristic is None:
        if goal is None:
            raise ValueError("a heuristic is needed when the goal is a predicate")
        heuristic = lambda v: graph.heuristic(v, goal)  # noqa: E731
    if is_goal is None:
        is_goal = lambda v: v == goal  # noqa: E731
    t0 = time.perf_counter()
    deadline = None if time_limit is None else t0 + time_limit
    seq = itertools.count()
    g: dict[Hashable, float] = {start: 0.0}
    parent: dict[Hashable, Hashable] = {}
    closed: set[Hashable] = set()
    heap = [(weight * heuristic(start), -0.0, next(seq), start)]
    n = 0
    status = SearchStatus.NO_PATH
    found = None
    while heap:
        _, neg_g, _, u = heapq.heappop(heap)
        if u in closed or -neg_g > g[u]:
            continue  # stale entry
        if is_goal(u):
            status, found = SearchStatus.SUCCESS, u
            break
        if max_expansions is not None and n >= max_expansions:
            status = SearchStatus.EXPANSION_LIMIT
            break
        if deadline is not None and (n & 63) == 0 and time.perf_counter() > deadline:
            status = SearchStatus.TIME_LIMIT
            break
        closed.add(u)
        n += 1
        g_u = g[u]
        for v, c in graph.successors(u):
            if v in closed:
                continue
            nv = g_u + c
            if nv < g.get(v, INF):
                g[v] = nv
                parent[v] = u
                heapq.heappush(heap, (nv + weight * heuristic(v), -nv, next(seq), v))
    dt = time.perf_counter() - t0
    if found is None:
        return AStarResult(status, [], INF, n, dt)
    path = [found]
    while path[-1] != start:
        path.append(parent[path[-1]])
    path.reverse()
    return AStarResult(status, path, g[found], n, dt)
