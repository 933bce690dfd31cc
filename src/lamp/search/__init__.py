"""Object-level search: the SE(2) object lattice, D* Lite (LAMP-Lazy), weighted A* (GCo).

* :class:`ObjectLattice` — goal-anchored lattice of object poses with lazily checked,
  cached node and edge validity (``lamp.geometry.object_space.ObjectSpace``).
* :class:`DStarLite` — incremental shortest paths to the goal from a moving (possibly
  continuous, virtual) start, with edge-cost updates (the paper's Alg. 2).
* :func:`weighted_astar` — weighted A* over the same graph protocol.
* :class:`GCoLattice`, :func:`gco_object_path` — GCo's object-only weighted A*.
"""

from lamp.search.astar import AStarResult, weighted_astar
from lamp.search.dstar_lite import DStarLite
from lamp.search.gco_lattice import GCoLattice, gco_object_path, gco_search
from lamp.search.graph import Graph, SearchStatus
from lamp.search.lattice import PRIMITIVES, ObjectLattice

__all__ = [
    "PRIMITIVES",
    "AStarResult",
    "DStarLite",
    "GCoLattice",
    "Graph",
    "ObjectLattice",
    "SearchStatus",
    "gco_object_path",
    "gco_search",
    "weighted_astar",
]
