"""Shortest paths of a disk among polygonal obstacles, never longer than the true ones.

A disk of radius ``rho`` whose centre moves from ``a`` to ``b`` without overlapping the
obstacles keeps its centre out of the obstacles grown by ``rho``. :class:`GrownObstacles`
computes the length of the shortest path of a point around those grown obstacles: the
visibility graph of their vertices (every shortest path among polygons bends only at
their vertices) searched with Dijkstra (SciPy).

Guarantee, what makes it a lower bound (``tests/test_geodesic.py``): the result never
exceeds the length of any path of the disk's centre that keeps the disk clear of the
obstacles, because every approximation errs on the short side: Shapely's round buffer
is a polygon inscribed in the true grown outline (its vertices on the offset curve), the
grown obstacles are shrunk by ``SHRINK`` before segments are tested against them (a path
may graze them, and pass between two that touch). With ``merge``, obstacles that meet are
merged first, so a way never slips through a joint of zero width: the result is then a
lower bound for paths that keep some distance from the obstacles (a robot's centre
keeps its radius), not for those that graze two at once. With a ``workspace`` (W, H),
the outside of ``[0, W] x [0, H]`` is an obstacle too (a disk that must stay inside it).
It is at least the straight-line distance, and equals it when the straight segment is
clear. Deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely
from scipy.sparse import csr_array
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

__all__ = ["MATRIX_BLOCK", "QUAD_SEGS", "SHRINK", "GrownObstacles"]

#: Segments per quarter circle of the grown outlines (Shapely's ``quad_segs``): more is
#: tighter and slower; the bound is valid at any value.
QUAD_SEGS = 2
#: How far (m) the grown obstacles shrink before visibility is tested: a segment that only
#: touches an outline counts as clear.
SHRINK = 1e-7
#: Rows handled together (memory): the vertices whose pairs the visibility graph tests at
#: once, and the sources :meth:`GrownObstacles.distance_matrix` searches at once (this many
#: rows of distances to every vertex).
MATRIX_BLOCK = 256


class GrownObstacles:
    """``obstacles`` (Shapely geometries) grown by ``rho`` (m), and the outside of
    ``workspace`` (W, H) when given, merged where they meet with ``merge`` (module doc),
    with the visibility graph of their vertices built once; :meth:`distance` answers
    queries between free points."""

    def __init__(self, obstacles: Sequence[shapely.Geometry], rho: float,
                 workspace: tuple[float, float] | None = None, merge: bool = False) -> None:
        self.rho = max(0.0, float(rho))
        parts = [g for g in obstacles if not g.is_empty]
        if workspace is not None:  # the outside, as four strips
            w, h = (float(v) for v in workspace)
            m = 1.0 + self.rho
            parts += [shapely.box(-m, -m, 0, h + m), shapely.box(w, -m, w + m, h + m),
                      shapely.box(-m, -m, w + m, 0), shapely.box(-m, h, w + m, h + m)]
        grown = [g.buffer(self.rho, quad_segs=QUAD_SEGS) if self.rho > 0 else g for g in parts]
        pieces = shapely.get_parts(shapely.union_all(grown)) if merge and grown else grown
        self._pieces = [g.buffer(-SHRINK) for g in pieces]
        self._pieces = [g for g in self._pieces if not g.is_empty]
        self._tree = shapely.STRtree(self._pieces)
        # prepared once: a segment is then tested against a large outline in log time
        self._prepared = np.array(self._pieces, dtype=object)
        shapely.prepare(self._prepared)
        rings = [np.asarray(shapely.get_coordinates(shapely.get_exterior_ring(g)))[:-1]
                 for g in grown if isinstance(g, shapely.Polygon) and not g.is_empty]
        rings = [r for r in rings if len(r) >= 3]
        points = np.vstack(rings) if rings else np.zeros((0, 2))
        # each vertex's neighbours on its ring, for the tangency test
        prev = np.vstack([np.roll(r, 1, axis=0) for r in rings]) if rings else points
        nxt = np.vstack([np.roll(r, -1, axis=0) for r in rings]) if rings else points
        # a vertex inside another grown obstacle is on no path
        keep = np.ones(len(points), bool)
        if len(points):
            hit, _ = self._tree.query(shapely.points(points), predicate="intersects")
            keep[hit] = False
        self.vertices, self._prev, self._next = points[keep], prev[keep], nxt[keep]
        self._edges = self._vertex_edges()

    @property
    def n_edges(self) -> int:
        """The visibility graph's edges between vertices (each pair once)."""
        return len(self._edges[0])

    def _clear(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether each segment ``a[i]``-``b[i]`` misses the (shrunk) grown obstacles."""
        ok = np.ones(len(a), bool)
        if len(a) == 0 or not self._pieces:
            return ok
        segs = shapely.linestrings(np.stack([a, b], axis=1))
        seg, piece = self._tree.query(segs)  # boxes that meet
        ok[seg[shapely.intersects(self._prepared[piece], segs[seg])]] = False
        return ok

    def _tangent(self, v: np.ndarray, other: np.ndarray) -> np.ndarray:
        """Whether the segment from vertex ``v[i]`` (an index) to ``other[i]`` leaves its
        obstacle tangentially: both ring neighbours of the vertex on one side of it. A
        shortest path bends only at vertices it is tangent at (the reduced visibility
        graph), so the other segments are never on one."""
        d = other - self.vertices[v]
        e, f = self._prev[v] - self.vertices[v], self._next[v] - self.vertices[v]
        cp = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
        cn = d[:, 0] * f[:, 1] - d[:, 1] * f[:, 0]
        return cp * cn >= 0

    def _vertex_edges(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, length) of the clear segments between vertices ``i < j`` tangent at both
        ends, in the order of ``np.triu_indices``; :data:`MATRIX_BLOCK` rows of pairs at a
        time (memory)."""
        p, n = self.vertices, len(self.vertices)
        parts = []
        for r0 in range(0, n, MATRIX_BLOCK):
            i, j = _rows_above(n, r0, min(r0 + MATRIX_BLOCK, n))
            t = self._tangent(i, p[j]) & self._tangent(j, p[i])
            i, j = i[t], j[t]
            ok = self._clear(p[i], p[j])
            i, j = i[ok], j[ok]
            parts.append((i, j, np.hypot(*(p[i] - p[j]).T)))
        if not parts:
            return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
        i, j, d = (np.concatenate(c) for c in zip(*parts, strict=True))
        return i, j, d

    def _visible_pairs(self, p: np.ndarray, q: np.ndarray, offset: np.ndarray | None = None,
                       below: float = math.inf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, length) of the clear segments from ``p[i]`` to vertex ``q[j]`` that are
        tangent at the vertex; with ``offset``, only those with ``offset[j] + length <
        below`` (the others are not tested for clearance)."""
        i, j = (a.ravel() for a in np.meshgrid(np.arange(len(p)), np.arange(len(q)),
                                              indexing="ij"))
        t = self._tangent(j, p[i])
        i, j = i[t], j[t]
        length = np.hypot(*(p[i] - q[j]).T)
        if offset is not None:
            near = offset[j] + length < below
            i, j, length = i[near], j[near], length[near]
        ok = self._clear(p[i], q[j])
        return i[ok], j[ok], length[ok]

    def blocks(self, region: shapely.Geometry) -> bool:
        """Whether ``region`` meets the (shrunk) grown obstacles."""
        return len(self._tree.query(region, predicate="intersects")) > 0

    def _graph(self, *ends: np.ndarray) -> csr_array:
        """The visibility graph with ``ends[e]`` as node ``V + e``."""
        V = len(self.vertices)
        vi, vj, vd = self._edges
        rows, cols, w = [vi, vj], [vj, vi], [vd, vd]
        for e, p in enumerate(ends):
            _, pj, pd = self._visible_pairs(np.array([p]), self.vertices)
            rows += [np.full(len(pj), V + e), pj]
            cols += [pj, np.full(len(pj), V + e)]
            w += [pd, pd]
        # a zero length (a point on a vertex) would read as no edge: a hair longer
        weights = np.maximum(np.concatenate(w), 1e-12)
        n = V + len(ends)
        return csr_array((weights, (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))

    def distance(self, a: Sequence[float], b: Sequence[float]) -> float:
        """The shortest path's length from ``a`` to ``b`` (x, y) around the grown
        obstacles (module docstring); the straight line when that is clear; ``inf`` when
        the grown obstacles separate them."""
        a, b = np.asarray(a, float)[:2], np.asarray(b, float)[:2]
        straight = float(math.dist(a, b))
        if self._clear(a[None], b[None])[0]:
            return straight
        V = len(self.vertices)
        d = dijkstra(self._graph(a, b), directed=False, indices=V)[V + 1]
        return max(straight, float(d))

    def distances(self, a: Sequence[float], targets: np.ndarray, below: float = math.inf
                  ) -> np.ndarray:
        """:meth:`distance` from ``a`` to each of ``targets`` (n, 2), with one search from
        ``a``: each target's is the straight line when that is clear, else the least over
        the vertices it sees tangentially of their distance from ``a`` plus the segment.
        A distance of at least ``below`` may be given as ``below`` instead (fewer segments
        are tested)."""
        a = np.asarray(a, float)[:2]
        t = np.asarray(targets, float).reshape(-1, 2)
        straight = np.hypot(*(t - a).T)
        clear = self._clear(np.broadcast_to(a, t.shape), t)
        out = np.where(clear, straight, np.inf)
        if clear.all():
            return out
        V = len(self.vertices)
        d = dijkstra(self._graph(a), directed=False, indices=V)[:V]
        i, j, length = self._visible_pairs(t, self.vertices, offset=d, below=below)
        np.minimum.at(out, i, d[j] + length)
        return np.maximum(np.minimum(out, max(below, 0.0)), straight)

    def _near_vertices(self, pts: np.ndarray, below: float, ends: np.ndarray,
                       owner: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, length) of the clear segments from ``pts[i]`` to vertex ``j``, tangent at
        the vertex, where a way from ``pts[i]`` through the vertex to one of its other ends
        could be shorter than ``below``: ``|pts[i] - v| + |v - e| < below`` for some
        ``e = ends[k]`` with ``owner[k] == i`` (``inf``: every vertex)."""
        if not math.isfinite(below) or len(self.vertices) == 0:
            return self._visible_pairs(pts, self.vertices)
        near = cKDTree(self.vertices).query_ball_point(pts, below)
        order = np.argsort(owner, kind="stable")
        ends, first = ends[order], np.searchsorted(owner[order], np.arange(len(pts) + 1))
        keep_i, keep_j = [], []
        for a, cand in enumerate(near):
            if not cand or first[a] == first[a + 1]:
                continue
            v = self.vertices[cand]
            e = ends[first[a]:first[a + 1]]
            via = np.hypot(*(v - pts[a]).T)[:, None] + np.hypot(
                v[:, None, 0] - e[None, :, 0], v[:, None, 1] - e[None, :, 1])
            c = np.asarray(cand)[via.min(axis=1) < below]
            keep_i.append(np.full(len(c), a))
            keep_j.append(c)
        if not keep_i:
            return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
        i, j = np.concatenate(keep_i), np.concatenate(keep_j).astype(np.int64)
        keep = self._tangent(j, pts[i])
        i, j = i[keep], j[keep]
        ok = self._clear(pts[i], self.vertices[j])
        i, j = i[ok], j[ok]
        return i, j, np.hypot(*(pts[i] - self.vertices[j]).T)

    def distance_matrix(self, P: np.ndarray, Q: np.ndarray, below: float = math.inf
                        ) -> np.ndarray:
        """``D[i, j]`` = :meth:`distance` from ``P[i]`` to ``Q[j]`` ((n, 2) and (m, 2)
        points), for many pairs at once; where it is at least ``below`` it may be given
        as ``max(below, straight line)`` instead, which is never more. A pair is searched
        only when its straight line is shorter than ``below`` and not clear, and its ends
        are joined only to the vertices in its ellipse ``|a - v| + |v - b| < below`` (a
        way shorter than ``below`` leaves and reaches its ends from no other): with a
        finite ``below`` the cost grows with the pairs and vertices near each other, not
        with their product. One search per point of ``P``
        with such a pair, :data:`MATRIX_BLOCK` at a time (SciPy's Dijkstra, cut at
        ``below``)."""
        P = np.asarray(P, float).reshape(-1, 2)
        Q = np.asarray(Q, float).reshape(-1, 2)
        straight = np.hypot(P[:, None, 0] - Q[None, :, 0], P[:, None, 1] - Q[None, :, 1])
        out = np.maximum(straight, below)
        pi, qj = np.nonzero(straight < below)
        clear = self._clear(P[pi], Q[qj])
        out[pi[clear], qj[clear]] = straight[pi[clear], qj[clear]]
        pi, qj = pi[~clear], qj[~clear]
        if len(pi) == 0:
            return out
        V = len(self.vertices)
        src = np.unique(pi)
        si, sv, sl = self._near_vertices(P[src], below, Q[qj], np.searchsorted(src, pi))
        ti, tv, tl = self._near_vertices(Q, below, P[pi], qj)
        vi, vj, vd = self._edges
        # nodes: the vertices, then each source of ``src`` joined to the vertices it sees
        n = V + len(src)
        graph = csr_array((np.maximum(np.concatenate([vd, vd, sl, sl]), 1e-12),
                           (np.concatenate([vi, vj, V + si, sv]),
                            np.concatenate([vj, vi, sv, V + si]))), shape=(n, n))
        order = np.argsort(qj, kind="stable")
        pi, qj = pi[order], qj[order]
        t_order = np.argsort(ti, kind="stable")
        tv, tl = tv[t_order], tl[t_order]
        t_start = np.searchsorted(ti[t_order], np.arange(len(Q) + 1))
        row_of = np.searchsorted(src, pi)
        for b0 in range(0, len(src), MATRIX_BLOCK):
            rows = np.arange(b0, min(b0 + MATRIX_BLOCK, len(src)))
            d = dijkstra(graph, directed=False, indices=V + rows, limit=below)[:, :V]
            mine = (row_of >= b0) & (row_of < rows[-1] + 1)
            bp, bq, br = pi[mine], qj[mine], row_of[mine] - b0  # sorted by ``bq``
            cuts = np.flatnonzero(np.diff(bq)) + 1
            for lo, hi in zip(np.r_[0, cuts], np.r_[cuts, len(bq)], strict=True):
                q, at = bq[lo], slice(lo, hi)
                seen = slice(t_start[q], t_start[q + 1])
                if seen.start == seen.stop:
                    continue
                via = (d[br[at]][:, tv[seen]] + tl[seen]).min(axis=1)
                out[bp[at], q] = np.maximum(np.minimum(via, out[bp[at], q]),
                                            straight[bp[at], q])
        return out

    def path(self, a: Sequence[float], b: Sequence[float]) -> np.ndarray | None:
        """The shortest path's points from ``a`` to ``b`` (x, y), ends included, whose
        length is :meth:`distance` (up to rounding); ``[a, b]`` when the straight line is
        clear; None when the grown obstacles separate them."""
        a, b = np.asarray(a, float)[:2], np.asarray(b, float)[:2]
        if self._clear(a[None], b[None])[0]:
            return np.array([a, b])
        V = len(self.vertices)
        d, pred = dijkstra(self._graph(a, b), directed=False, indices=V,
                           return_predecessors=True)
        if not math.isfinite(d[V + 1]):
            return None
        nodes, n = [], V + 1
        while n >= 0:
            nodes.append(n)
            n = int(pred[n])
        pts = np.vstack([self.vertices, a, b])
        return pts[nodes[::-1]]


def _rows_above(n: int, r0: int, r1: int) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(i, j)``, ``r0 <= i < r1``, ``i < j < n``, in the order of
    ``np.triu_indices(n, 1)``."""
    counts = n - 1 - np.arange(r0, r1)
    i = np.repeat(np.arange(r0, r1), counts)
    start = np.cumsum(counts) - counts
    j = np.arange(len(i)) - np.repeat(start, counts) + np.repeat(np.arange(r0, r1), counts) + 1
    return i, j
