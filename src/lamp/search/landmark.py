"""A landmark potential for the object lattice: 2D geodesic distances from one point.

The octile metric of :class:`~lamp.search.lattice.ObjectLattice` ignores obstacles, so a
search guided by it expands every pose whose straight-line estimate is below the cost of
the detour the obstacles force; on a long route through clutter that is a band whose area
grows with the square of the route. This module adds what the metric misses, as an ALT
(landmark) bound: ``|D(a) - D(b)|`` for a potential ``D`` that is 1-Lipschitz along every
lattice edge (``|D(u) - D(v)| <=`` the edge's translation cost). By the triangle
inequality along any path, ``|D(a) - D(b)|`` is then a lower bound of the translation cost
of every lattice path from ``a`` to ``b``, and it obeys the triangle inequality itself for
any values of ``D``.

``D`` is the shortest 8-connected path length (axis step ``step``, diagonal ``step *
sqrt(2)``) from the landmark over the *passable* lattice positions. A position is
impassable only when no heading can place the object there: when the disk inscribed in
the (inflated) footprint about its origin, contained in the footprint at every heading,
meets an obstacle (exact Shapely distance) or leaves the workspace. Every valid lattice
node therefore lies on a passable position and every lattice edge joins two passable
8-neighbours (or one position to itself), so ``D`` is 1-Lipschitz along it. Positions not
connected to the landmark all get one value above every finite ``D`` (no lattice edge
leaves their component, so the bound between components, finite, is still below the
infinite true cost).

A continuous position ``p`` off the grid gets ``D(p)`` from the passable positions ``v``
within ``radius`` of it: the smallest value in ``[max_v (D(v) - octile(p - v)), min_v
(D(v) + octile(p - v))]`` when that interval is not empty (then ``|D(p) - D(v)| <=
octile(p - v)`` for each of them), its midpoint otherwise. The lattice costs a connecting
motion by the full metric, so whatever ``D(p)`` is, that cost is never below the bound.

Guarantees (``tests/test_landmark.py``): every valid lattice node is passable; ``|D(u) -
D(v)|`` is at most the translation cost of every lattice edge; the resulting heuristic
never exceeds the cheapest path cost (plain Dijkstra on random maps).
"""

from __future__ import annotations

import heapq
import math

import numba
import numpy as np
import shapely

from lamp.geometry.object_space import ObjectSpace, inflated_geometry
from lamp.geometry.shapes import obstacle_geometry
from lamp.search.metric import OCTILE_MINOR

#: shrinks the inscribed disk a little so that rounding never blocks a free position
_RADIUS_SLACK = 1e-6


def inscribed_radius(space: ObjectSpace) -> float:
    """Radius of the largest disk about the object's origin inside its inflated footprint
    (0 when the origin is not inside): the footprint contains it at every heading."""
    geom = inflated_geometry(space.shape, (0.0, 0.0, 0.0), space.inflation)
    origin = shapely.Point(0.0, 0.0)
    if not geom.contains(origin):
        return 0.0
    return max(0.0, float(geom.exterior.distance(origin)) - _RADIUS_SLACK)


def passable_positions(space: ObjectSpace, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """(len(xs), len(ys)) bool: whether some heading might place the object at (x, y).

    False only when the inscribed disk (:func:`inscribed_radius`) meets an obstacle or
    leaves the workspace, so a free pose is never on an impassable position."""
    r = inscribed_radius(space)
    w, h = space.workspace
    ok = np.ones((len(xs), len(ys)), dtype=bool)
    if r <= 0.0:
        return ok
    ok &= ((xs >= r) & (xs <= w - r))[:, None]
    ok &= ((ys >= r) & (ys <= h - r))[None, :]
    for obstacle in space.obstacles:
        geom = obstacle_geometry(obstacle)
        x0, y0, x1, y1 = geom.bounds
        i0, i1 = np.searchsorted(xs, x0 - r, "left"), np.searchsorted(xs, x1 + r, "right")
        j0, j1 = np.searchsorted(ys, y0 - r, "left"), np.searchsorted(ys, y1 + r, "right")
        if i1 <= i0 or j1 <= j0:
            continue
        gx, gy = np.meshgrid(xs[i0:i1], ys[j0:j1], indexing="ij")
        near = shapely.distance(geom, shapely.points(gx.ravel(), gy.ravel())) < r
        ok[i0:i1, j0:j1] &= ~near.reshape(gx.shape)
    return ok


@numba.njit(cache=True)
def _octile_dijkstra(passable: np.ndarray, seeds: np.ndarray, seed_cost: np.ndarray,
                     step: float) -> np.ndarray:
    """Shortest 8-connected path lengths over ``passable`` cells from the seed cells
    (flat indices, starting at their costs); ``inf`` where unreachable."""
    n_i, n_j = passable.shape
    dist = np.full(n_i * n_j, np.inf)
    heap = [(0.0, np.int64(0))]
    heap.pop()
    for s in range(seeds.shape[0]):
        c = seed_cost[s]
        if c < dist[seeds[s]]:
            dist[seeds[s]] = c
            heapq.heappush(heap, (c, np.int64(seeds[s])))
    diag = step * math.sqrt(2.0)
    while len(heap) > 0:
        d, u = heapq.heappop(heap)
        if d > dist[u]:
            continue
        ui = u // n_j
        uj = u - ui * n_j
        for di in range(-1, 2):
            for dj in range(-1, 2):
                if di == 0 and dj == 0:
                    continue
                vi = ui + di
                vj = uj + dj
                if vi < 0 or vi >= n_i or vj < 0 or vj >= n_j or not passable[vi, vj]:
                    continue
                nd = d + (diag if di != 0 and dj != 0 else step)
                v = vi * n_j + vj
                if nd < dist[v]:
                    dist[v] = nd
                    heapq.heappush(heap, (nd, np.int64(v)))
    return dist


class LandmarkPotential:
    """``D`` over the positions ``(x0 + i * step, y0 + j * step)``, ``0 <= i < n_i``,
    ``0 <= j < n_j``, from ``landmark``; see the module docstring.

    Args:
        space: the object's collision queries (its shape, inflation and obstacles).
        origin: (x0, y0), the position of cell (0, 0).
        step: the grid step (m).
        shape: (n_i, n_j).
        landmark: (x, y) the distances are measured from.
        radius: the neighbourhood that gives an off-grid position its value (m).
    """

    def __init__(self, space: ObjectSpace, origin: tuple[float, float], step: float,
                 shape: tuple[int, int], landmark: tuple[float, float], radius: float) -> None:
        n_i, n_j = shape
        self.origin = (float(origin[0]), float(origin[1]))
        self.step = float(step)
        self.shape = (int(n_i), int(n_j))
        self.radius = float(radius)
        xs = self.origin[0] + step * np.arange(n_i)
        ys = self.origin[1] + step * np.arange(n_j)
        self.passable = passable_positions(space, xs, ys)
        lx, ly = float(landmark[0]), float(landmark[1])
        cells = self._near(lx, ly, max(radius, step * math.sqrt(2.0)))
        seeds = np.array([c for c, _ in cells], dtype=np.int64)
        cost = np.array([o for _, o in cells], dtype=float)
        dist = _octile_dijkstra(self.passable, seeds, cost, self.step)
        finite = np.isfinite(dist)
        #: the value of every position not connected to the landmark (and impassable ones)
        self.unreachable = float(np.max(dist[finite], initial=0.0)) + 1.0
        dist[~finite] = self.unreachable
        #: (n_i * n_j,) D at the grid positions, flat index ``i * n_j + j``
        self.values = dist
        self._cache: dict[tuple[float, float], float] = {}

    def _near(self, x: float, y: float, radius: float) -> list[tuple[int, float]]:
        """Passable cells within ``radius`` (max norm) of (x, y) as (flat index, octile)."""
        n_i, n_j = self.shape
        fi = (x - self.origin[0]) / self.step
        fj = (y - self.origin[1]) / self.step
        r = radius / self.step
        i0, i1 = max(0, math.floor(fi - r)), min(n_i - 1, math.ceil(fi + r))
        j0, j1 = max(0, math.floor(fj - r)), min(n_j - 1, math.ceil(fj + r))
        out = []
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                if not self.passable[i, j]:
                    continue
                dx = abs(x - (self.origin[0] + i * self.step))
                dy = abs(y - (self.origin[1] + j * self.step))
                out.append((i * n_j + j, max(dx, dy) + OCTILE_MINOR * min(dx, dy)))
        return out

    def at(self, x: float, y: float) -> float:
        """D at a continuous position (exactly the grid value on a grid position)."""
        fi = (x - self.origin[0]) / self.step
        fj = (y - self.origin[1]) / self.step
        i, j = round(fi), round(fj)
        n_i, n_j = self.shape
        if abs(fi - i) < 1e-9 and abs(fj - j) < 1e-9 and 0 <= i < n_i and 0 <= j < n_j:
            return float(self.values[i * n_j + j])
        key = (x, y)
        got = self._cache.get(key)
        if got is not None:
            return got
        cells = self._near(x, y, self.radius)
        if not cells:
            value = self.unreachable
        else:
            hi = max(self.values[c] - o for c, o in cells)
            lo = min(self.values[c] + o for c, o in cells)
            value = float(hi if hi <= lo else 0.5 * (hi + lo))
        if len(self._cache) > 4096:
            self._cache.clear()
        self._cache[key] = value
        return value

    @property
    def nbytes(self) -> int:
        return int(self.values.nbytes + self.passable.nbytes)


def _potential_from(space: ObjectSpace, start: tuple[float, float], step: float
                    ) -> LandmarkPotential:
    """The potential over the workspace grid of side ``step`` through ``start``, from it."""
    sx, sy = float(start[0]), float(start[1])
    w, h = space.workspace
    origin = (sx - step * math.floor(sx / step), sy - step * math.floor(sy / step))
    shape = (int(math.floor((w - origin[0]) / step)) + 1,
             int(math.floor((h - origin[1]) / step)) + 1)
    return LandmarkPotential(space, origin, step, shape, (sx, sy), 2.0 * step)


def _goal_end(p: LandmarkPotential, goal: tuple[float, float]) -> tuple[int, float] | None:
    """The cell within two steps of ``goal`` connected to the start that is cheapest to end
    at, with its route length plus the octile rest to ``goal`` (ties by cell index); None
    when no such cell is connected to the start."""
    ends = [(p.values[c] + o, c) for c, o in p._near(float(goal[0]), float(goal[1]), p.radius)
            if p.values[c] < p.unreachable]
    if not ends:
        return None
    length, cell = min(ends)
    return cell, float(length)


def route_length(space: ObjectSpace, start: tuple[float, float], goal: tuple[float, float],
                 step: float) -> float | None:
    """The length of the object's shortest route from ``start`` to ``goal`` as the potential
    sees it: the shortest 8-connected path over the passable positions (module docstring)
    of the grid of side ``step`` through ``start`` to a position within two steps of
    ``goal``, plus the octile distance from there (the least such sum). None when no
    position near the goal is connected to the start. An off-grid goal is not valued as
    :meth:`LandmarkPotential.at` values it: near a wall that mixes in the positions beyond
    it, and a goal walled off from the start would get a length, not None.

    Guarantees (``tests/test_landmark.py``): on a map without obstacles it is the octile
    distance from start to goal (within a grid step); it is never below the straight-line
    distance (within a grid step); a wall the inscribed disk cannot pass adds at least the
    detour around it; a goal walled off from the start gives None. Cost: one Dijkstra over
    the workspace's grid (a 50 m map at 0.1 m: 250 k positions).
    """
    end = _goal_end(_potential_from(space, start, step), goal)
    return None if end is None else end[1]


def route_path(space: ObjectSpace, start: tuple[float, float], goal: tuple[float, float],
               step: float) -> np.ndarray | None:
    """(N, 2) the route :func:`route_length` measures: ``start``, the passable grid
    positions of a steepest descent of the potential from the goal's cheapest neighbour
    (within two steps) down to a cell beside the start, then ``goal``; None when the goal
    is not connected to the start.

    Guarantees (``tests/test_landmark.py``): it begins at ``start`` and ends at ``goal``;
    its grid positions are passable and 8-neighbours in turn; its length is the route
    length within two grid steps. Every step of the descent lowers the potential (the
    cell's Dijkstra predecessor is one such neighbour), so it ends, at a cell the search
    was seeded with: within two steps of the start."""
    p = _potential_from(space, start, step)
    end = _goal_end(p, goal)
    if end is None:
        return None
    u = end[0]
    n_i, n_j = p.shape
    path = [(float(goal[0]), float(goal[1]))]
    while True:
        i, j = divmod(u, n_j)
        path.append((p.origin[0] + i * p.step, p.origin[1] + j * p.step))
        best = u
        for di in (-1, 0, 1):
            for dj in (-1, 0, 1):
                vi, vj = i + di, j + dj
                if 0 <= vi < n_i and 0 <= vj < n_j and p.passable[vi, vj]:
                    v = vi * n_j + vj
                    if p.values[v] < p.values[best]:
                        best = v
        if best == u:
            break
        u = best
    path.append((float(start[0]), float(start[1])))
    return np.array(path[::-1])
