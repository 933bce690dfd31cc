"""Exact cost-to-goal on a graph, computed on demand by a resumable backward Dijkstra.

LAMP-A* needs a heuristic for every object pose it reaches. The SE(2) metric ignores
obstacles, so in clutter it points into dead ends and the search floods them state by
state. The object-only shortest-path cost to the goal over the same lattice is a far
better guide and stays a lower bound on the object's travel. ``ReverseDistance`` runs
Dijkstra backwards from the goal (over ``predecessors``) and stops as soon as the queried
vertex is settled; the next query resumes where the last one stopped (the idea of Silver's
Reverse Resumable A*, 2005, without the start-directed ordering, so that any vertex can be
asked). Each vertex is settled at most once over all queries.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Hashable

from lamp.search.graph import Graph


class ReverseDistance:
    """``distance(u)``: the cheapest path cost from ``u`` to ``goal`` (``inf`` if none)."""

    def __init__(self, graph: Graph, goal: Hashable) -> None:
        self.graph = graph
        self.goal = goal
        self._settled: dict[Hashable, float] = {}
        self._best: dict[Hashable, float] = {goal: 0.0}
        self._tie = itertools.count()
        self._open: list[tuple[float, int, Hashable]] = [(0.0, next(self._tie), goal)]

    @property
    def n_settled(self) -> int:
        return len(self._settled)

    def distance(self, u: Hashable) -> float:
        done = self._settled.get(u)
        if done is not None:
            return done
        while self._open:
            d, _, v = heapq.heappop(self._open)
            if v in self._settled:
                continue  # a stale entry: v was settled through a cheaper one
            self._settled[v] = d
            for w, c in self.graph.predecessors(v):  # edges w -> v
                nd = d + c
                if w not in self._settled and nd < self._best.get(w, math.inf):
                    self._best[w] = nd
                    heapq.heappush(self._open, (nd, next(self._tie), w))
            if v == u:
                return d
        return math.inf  # the search is exhausted: u cannot reach the goal
