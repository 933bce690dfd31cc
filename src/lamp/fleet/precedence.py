"""Implied precedence: a load whose goal would cut another's way starts after that one.

A load placed in a gap, a door or an aisle that another load still has to pass through
shuts that load's way for good: placed objects never move again. The start order prefers
to start such a load later (``teams.in_the_way``), but it judges by the straight hull of
the ways, and with robots enough both start at once anyway. :func:`goal_cuts` finds the
pairs for certain, once, when the schedule begins: object ``k`` *cuts* object ``j`` when
``j`` can reach its goal round the map's obstacles (``makeway.route_of``, from where
it stands) but cannot once ``k`` stands at its goal (``landmark.route_length`` with
``k``'s goal footprint as one more obstacle). Only pairs whose goal footprint comes near
the way (``j``'s bounding radius and a robot diameter) are checked, so the cost is one
route per object and one more per such pair; not those where ``k``'s goal is where ``j``
stands (within a robot diameter): ``k`` waits for ``j`` to leave anyway, and where that is
a cycle (places rotated round) one makes way (``fleet.makeway``). ``Fleet`` starts ``k`` only once every
object it cuts is placed or given up. Pairs that cut each other (directly or round a
cycle: strongly connected components, SciPy) get no precedence: no order of placements
helps them, and waiting would only stall them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from scipy.sparse import csr_array
from scipy.sparse.csgraph import connected_components

from lamp.fleet.makeway import route_of
from lamp.geometry.object_space import ObjectSpace
from lamp.geometry.primitives import Obstacle
from lamp.geometry.shapes import obstacle_geometry, to_shapely
from lamp.scene.model import Scene
from lamp.search.landmark import route_length

__all__ = ["COARSE_CELLS", "goal_cuts"]

#: Grid cells across the map's longer side above which the routes' grid grows coarser
#: than 0.1 m (a 150 m map: 0.375 m): one route per object costs a Dijkstra over the map.
COARSE_CELLS = 400


def goal_cuts(scene: Scene, poses: np.ndarray, step: float | None = None,
              objects: Sequence[int] | None = None) -> dict[int, frozenset[int]]:
    """For each of ``objects`` (default: all) ``k``: the objects ``j`` whose way from
    ``poses[j]`` to their goal ``k`` placed at its goal would cut (module docstring),
    pairs on a cycle of that relation left out; routes on a grid of side ``step``
    (default: 0.1 m, coarser on maps over ``COARSE_CELLS`` of it across). Deterministic."""
    if step is None:
        step = max(0.1, max(scene.workspace) / COARSE_CELLS)
    objs = list(range(len(scene.objects))) if objects is None else list(objects)
    poses = np.asarray(poses, float)
    r = float(scene.robot_radius)
    ways: dict[int, shapely.LineString] = {}
    for j in objs:
        path = route_of(scene, j, poses[j], step)
        if path is not None:
            ways[j] = shapely.LineString(path)
    edges = []
    for k in objs:
        placed = Obstacle(scene.objects[k].shape, scene.objects[k].goal)
        at_goal = obstacle_geometry(placed)
        for j, way in ways.items():
            obj = scene.objects[j]
            if j == k or not shapely.dwithin(way, at_goal, obj.shape.bounding_radius + 2 * r):
                continue
            if shapely.dwithin(at_goal, to_shapely(obj.shape, poses[j]), 2 * r):
                continue  # k's goal is where j stands: j leaves first anyway (or makes way)
            space = ObjectSpace(obj.shape, scene.workspace, (*scene.obstacles, placed),
                                static=scene.fixed_obstacles)
            if route_length(space, (poses[j][0], poses[j][1]), (obj.goal[0], obj.goal[1]),
                            step) is None:
                edges.append((k, j))
    cuts: dict[int, set[int]] = {k: set() for k in objs}
    if edges:
        n = len(scene.objects)
        rows, cols = zip(*edges, strict=True)
        graph = csr_array((np.ones(len(edges)), (rows, cols)), shape=(n, n))
        _, label = connected_components(graph, directed=True, connection="strong")
        for k, j in edges:
            if label[k] != label[j]:
                cuts[k].add(j)
    return {k: frozenset(v) for k, v in cuts.items()}
