"""What the searches of :mod:`lamp.search` ask of a graph, and how a search ended."""

from __future__ import annotations

import enum
from collections.abc import Hashable, Iterable
from typing import Protocol

__all__ = ["Graph", "SearchStatus"]


class Graph(Protocol):
    """What D* Lite and A* need from a graph. Vertices are hashable.

    ``successors(u)`` / ``predecessors(v)`` list the finite-cost edges ``(u -> v)`` as
    ``(v, cost)`` / ``(u, cost)`` pairs; ``cost(u, v)`` is ``inf`` when there is no edge;
    ``heuristic(a, b)`` is a consistent lower bound of the cost from ``a`` to ``b`` with the
    triangle inequality (a virtual start's edges may cost less: see the departures in
    :mod:`lamp.search.dstar_lite`).
    """

    def successors(self, u: Hashable) -> Iterable[tuple[Hashable, float]]: ...

    def predecessors(self, v: Hashable) -> Iterable[tuple[Hashable, float]]: ...

    def cost(self, u: Hashable, v: Hashable) -> float: ...

    def heuristic(self, a: Hashable, b: Hashable) -> float: ...


class SearchStatus(enum.Enum):
    SUCCESS = "success"
    NO_PATH = "no_path"
    EXPANSION_LIMIT = "expansion_limit"
    TIME_LIMIT = "time_limit"
    NOT_INITIALIZED = "not_initialized"
