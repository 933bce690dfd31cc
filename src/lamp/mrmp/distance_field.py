"""Planning lattice over a :class:`RobotSpace` and heuristic distance fields on it.

The lattice has nodes at ``(a * L, b * L)`` (``L`` a multiple of the space's grid spacing
``h``) wherever the robot is free, and 8-connected edges (axis moves of length ``L``,
diagonal moves of length ``L * sqrt(2)``) wherever the whole straight motion is free.

Edge check (conservative and continuous): an edge runs along grid nodes spaced ``h``
(axis) or ``h * sqrt(2)`` (diagonal) apart, whose exact clearances ``c_a, c_b`` are in the
grid; between two such nodes the clearance is at least ``(c_a + c_b - |ab|) / 2``
(1-Lipschitz cone bound). Edges failing that bound by less than ``0.75 h`` (motions that
graze an obstacle) are decided by the exact analytic segment clearance instead.

:meth:`Lattice.field` is a full multi-source Dijkstra over the lattice (used as the
reference in tests; the planner resumes its own Dijkstra lazily, see
:mod:`lamp.mrmp.gspi`). Lattices are cached on their space (:func:`get_lattice`).
"""

from __future__ import annotations

import heapq
import math
from collections import OrderedDict
from typing import Any

import numba as nb
import numpy as np

from lamp.geometry.clearance_kernels import segment_clearance, segments_clearance
from lamp.geometry.robot_space import RobotSpace
from lamp.mrmp.obstacle_grid import get_grid, grid_clear_segments

__all__ = ["Lattice", "clear_segments", "get_lattice", "DIRS"]

# 8 lattice directions (da, db); index d and 7 - d are opposite.
DIRS = np.array(
    [[1, 0], [1, 1], [0, 1], [-1, 1], [1, -1], [0, -1], [-1, -1], [-1, 0]], dtype=np.int64
)
_FIELD_CACHE_SIZE = 16
#: Lattice rows whose edges are decided together, against the obstacles near them.
EDGE_BAND = 32
#: Up to this many points or segments, links are looked up point by point and checked
#: against all obstacles at once (cheaper than tiles for LAMP's teams of a few robots).
FEW = 64
#: ... and while the segments times the obstacles stay below this: more (a few links
#: on a map of hundreds of obstacles) go through the bucket grid (the same decisions).
FEW_PAIRS = 4096


@nb.njit(cache=True)
def _dijkstra(
    nbr: np.ndarray, dlen: np.ndarray, seeds: np.ndarray, seed_cost: np.ndarray
) -> np.ndarray:
    """Multi-source Dijkstra on the lattice: nbr (V, 8) with -1 for no edge."""
    V = nbr.shape[0]
    dist = np.full(V, np.inf)
    heap = [(0.0, 0)]
    heap.pop()
    for k in range(seeds.shape[0]):
        s = seeds[k]
        if seed_cost[k] < dist[s]:
            dist[s] = seed_cost[k]
            heapq.heappush(heap, (seed_cost[k], s))
    done = np.zeros(V, dtype=np.bool_)
    while len(heap) > 0:
        d, u = heapq.heappop(heap)
        if done[u]:
            continue
        done[u] = True
        for e in range(8):
            v = nbr[u, e]
            if v < 0:
                continue
            nd = d + dlen[e]
            if nd < dist[v]:
                dist[v] = nd
                heapq.heappush(heap, (nd, v))
    return dist


@nb.njit(cache=True)
def _edge_bits(nbr: np.ndarray, va: np.ndarray, vb: np.ndarray, nb_: int,
               na: int) -> np.ndarray:
    """Each node's edges as bits (bit e: edge e), on the grid of lattice indices."""
    out = np.zeros((nb_, na), dtype=np.uint8)
    for v in range(nbr.shape[0]):
        m = 0
        for e in range(8):
            if nbr[v, e] >= 0:
                m |= 1 << e
        out[vb[v], va[v]] = m
    return out


@nb.njit(cache=True)
def _build_edges(
    F: np.ndarray, ids: np.ndarray, s: int, h: float, thr: float,
    circles: np.ndarray, verts: np.ndarray, ptr: np.ndarray, W: float, H: float,
    a_off: int, b_off: int, b_lo: int, b_hi: int, nbr: np.ndarray,
) -> None:
    """Fill the (V, 8) neighbour table ``nbr`` with the edges from the nodes of lattice
    rows ``b_lo`` .. ``b_hi - 1``: an edge exists when both nodes are free and the motion
    keeps clearance >= thr, by the cone bound over the grid nodes it passes through
    (exact field values), or, when that bound misses by less than 0.75 h, by the exact
    segment clearance against the obstacles given (those near the rows suffice).
    ``F[s * b, s * a]`` is lattice node ``(a + a_off, b + b_off)``."""
    nb_, na = ids.shape
    diag = h * math.sqrt(2.0)
    L = s * h
    for b in range(b_lo, b_hi):
        for a in range(na):
            u = ids[b, a]
            if u < 0:
                continue
            i0 = s * a
            j0 = s * b
            # forward directions 0 (1,0), 1 (1,1), 2 (0,1), 3 (-1,1); opposite = 7 - d
            for d in range(4):
                if d == 0:
                    da, db, di, dj, step_len = 1, 0, 1, 0, h
                elif d == 1:
                    da, db, di, dj, step_len = 1, 1, 1, 1, diag
                elif d == 2:
                    da, db, di, dj, step_len = 0, 1, 0, 1, h
                else:
                    da, db, di, dj, step_len = -1, 1, -1, 1, diag
                a2 = a + da
                b2 = b + db
                if a2 < 0 or a2 >= na or b2 >= nb_:
                    continue
                v = ids[b2, a2]
                if v < 0:
                    continue
                lo = np.inf
                for k in range(s):
                    f0 = F[j0 + k * dj, i0 + k * di]
                    f1 = F[j0 + (k + 1) * dj, i0 + (k + 1) * di]
                    c = 0.5 * (f0 + f1 - step_len)
                    if c < lo:
                        lo = c
                ok = lo >= thr
                if not ok and lo >= thr - 0.75 * h:
                    ax = (a + a_off) * L
                    ay = (b + b_off) * L
                    ok = segment_clearance(ax, ay, (a2 + a_off) * L, (b2 + b_off) * L, circles,
                                           verts, ptr, W, H) >= thr
                if ok:
                    nbr[u, d] = v
                    nbr[v, 7 - d] = u


class Lattice:
    """The free 8-connected lattice of step ``step`` over ``space`` (see module doc).

    Attributes: ``coords (V, 2)``; ``nbr (V, 8)`` neighbour ids or -1 in :data:`DIRS`
    order; ``dlen (8,)`` move lengths; ``ids (nb, na)`` node id per lattice index or -1,
    where ``ids[b, a]`` is the node at ``((a + a0) * L, (b + b0) * L)``, ``(a0, b0) =
    offset``. Lattice nodes sit at the same places whatever the space's window: those
    of the whole workspace's lattice that lie in the window, with the same edges.
    """

    def __init__(self, space: RobotSpace, step: float = 0.05) -> None:
        h = space.resolution
        s = int(round(step / h))
        if s < 1 or abs(s * h - step) > 1e-9:
            raise ValueError(
                f"lattice step must be a positive multiple of the grid spacing {h}, got {step!r}"
            )
        # what links() needs, not the space itself: a lattice is cached on its space, and a
        # reference back would make a cycle that keeps evicted spaces alive until a full GC
        self.workspace = space.workspace
        self.geometry = space.geometry
        #: (x0, y0, x1, y1) of the space's window
        self.window = space.window
        self.step = float(step)
        self.stride = s
        thr = space.threshold
        gi0, gj0, gi1, gj1 = space.window_nodes
        a0, b0 = -(-gi0 // s), -(-gj0 // s)  # first lattice index inside the window
        F = space.field[s * b0 - gj0:, s * a0 - gi0:]
        na = (gi1 // s) - a0 + 1
        nb_ = (gj1 // s) - b0 + 1
        self.offset = (a0, b0)
        Fl = F[: s * (nb_ - 1) + 1 : s, : s * (na - 1) + 1 : s]
        free = Fl >= thr
        ids = np.full((nb_, na), -1, dtype=np.int64)
        V = int(free.sum())
        ids[free] = np.arange(V)
        bb, aa = np.nonzero(free)
        self.ids = ids
        #: lattice index (a, b) of each node, as in ``ids[b, a]``
        self.va = aa.astype(np.int64)
        self.vb = bb.astype(np.int64)
        #: exact clearance of each node (the field is exact at grid nodes)
        self.node_clearance = np.ascontiguousarray(Fl[free], dtype=float)
        self.coords = np.ascontiguousarray(
            np.stack([(aa + a0) * step, (bb + b0) * step], axis=1), dtype=float)

        self.dlen = np.array([step * math.hypot(*d) for d in DIRS.tolist()], dtype=float)
        W, H = space.workspace
        # the edges from a band of rows lie in the band and the row above it: obstacles
        # farther than thr from that strip cannot decide one (``GeometrySet.near``)
        nbr = np.full((V, 8), -1, dtype=np.int64)
        x0, x1 = a0 * step, (a0 + na - 1) * step
        for lo in range(0, nb_, EDGE_BAND):
            hi = min(nb_, lo + EDGE_BAND)
            g = space.geometry.near((x0, (b0 + lo) * step, x1, (b0 + hi) * step), thr + h)
            _build_edges(F, ids, s, h, thr, g.circles, g.verts, g.ptr, W, H, a0, b0, lo, hi,
                         nbr)
        self.nbr = nbr
        self._edge_mask: np.ndarray | None = None
        self.V = V
        self._fields: OrderedDict[Any, np.ndarray] = OrderedDict()

    @property
    def edge_mask(self) -> np.ndarray:
        """(nb, na) uint8: bit e set where the node at that lattice index has edge e
        (0 where there is no node); made on first use."""
        if self._edge_mask is None:
            self._edge_mask = _edge_bits(self.nbr, self.va, self.vb, *self.ids.shape)
        return self._edge_mask

    # ---------------------------------------------------------------------------

    def nodes_near(self, p: np.ndarray, radius: float) -> np.ndarray:
        """Ids of free lattice nodes within ``radius`` of point ``p`` (sorted by distance)."""
        L = self.step
        nb_, na = self.ids.shape
        oa, ob = self.offset
        a0 = max(0, int(math.floor((p[0] - radius) / L)) - oa)
        a1 = min(na - 1, int(math.ceil((p[0] + radius) / L)) - oa)
        b0 = max(0, int(math.floor((p[1] - radius) / L)) - ob)
        b1 = min(nb_ - 1, int(math.ceil((p[1] + radius) / L)) - ob)
        if a1 < a0 or b1 < b0:
            return np.zeros(0, dtype=np.int64)
        blk = self.ids[b0 : b1 + 1, a0 : a1 + 1].ravel()
        blk = blk[blk >= 0]
        d = np.hypot(self.coords[blk, 0] - p[0], self.coords[blk, 1] - p[1])
        keep = d <= radius + 1e-12
        blk = blk[keep]
        return blk[np.argsort(d[keep], kind="stable")]

    def nodes_near_all(self, points: np.ndarray, radius: float) -> list[np.ndarray]:
        """:meth:`nodes_near` for each of ``points`` (K, 2), at once: the same ids in the
        same order (row-major over the lattice, then by distance, stable)."""
        L = self.step
        nb_, na = self.ids.shape
        if nb_ == 0 or na == 0 or self.V == 0:
            return [np.zeros(0, dtype=np.int64) for _ in range(len(points))]
        oa, ob = self.offset
        span = int(math.ceil(2 * radius / L)) + 2
        a0 = np.floor((points[:, 0] - radius) / L).astype(np.int64) - oa
        b0 = np.floor((points[:, 1] - radius) / L).astype(np.int64) - ob
        db, da = np.divmod(np.arange(span * span), span)  # row-major: b, then a
        A = a0[:, None] + da[None, :]
        B = b0[:, None] + db[None, :]
        inside = (A >= 0) & (na > A) & (B >= 0) & (nb_ > B)
        ids = np.where(inside, self.ids[np.clip(B, 0, nb_ - 1), np.clip(A, 0, na - 1)], -1)
        c = self.coords[np.maximum(ids, 0)]
        d = np.hypot(c[..., 0] - points[:, None, 0], c[..., 1] - points[:, None, 1])
        keep = (ids >= 0) & (d <= radius + 1e-12)
        d = np.where(keep, d, np.inf)
        order = np.argsort(d, axis=1, kind="stable")
        n = keep.sum(axis=1)
        srt = np.take_along_axis(ids, order, axis=1)
        return [srt[k, : n[k]] for k in range(len(points))]

    def any_node_near(self, points: np.ndarray, radius: float) -> np.ndarray:
        """(K,) bool: whether :meth:`nodes_near` of each of ``points`` (K, 2) is not empty
        (the window and test of :meth:`nodes_near_all`, compiled, without the sort)."""
        pts = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
        if self.ids.shape[0] == 0 or self.ids.shape[1] == 0 or self.V == 0:
            return np.zeros(len(pts), dtype=bool)
        oa, ob = self.offset
        return _any_node_near(pts, float(radius), self.step, oa, ob, self.ids, self.coords)

    def links(
        self, points: np.ndarray, radius: float, thresholds: np.ndarray,
        point_clearance: np.ndarray | None = None,
    ) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each continuous point: (node ids, lengths) of the lattice nodes within
        ``radius`` reachable by a straight motion whose exact clearance stays
        >= ``thresholds[k]``. With the points' exact ``point_clearance`` a motion whose
        ends are both clear by at least threshold + half its length is accepted without
        the exact segment check (clearance is 1-Lipschitz: every point of the motion is
        within half its length of an end), which gives the same links."""
        W, H = self.workspace
        g = self.geometry
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        cand = (self.nodes_near_all(pts, radius) if len(pts) > FEW
                else [self.nodes_near(p, radius) for p in pts])
        counts = [len(c) for c in cand]
        if sum(counts) == 0:
            return [(np.zeros(0, np.int64), np.zeros(0)) for _ in points]
        allc = np.concatenate(cand)
        src = np.repeat(np.asarray(points, dtype=float).reshape(-1, 2), counts, axis=0)
        dst = self.coords[allc]
        thr = np.repeat(np.asarray(thresholds, dtype=float), counts)
        lens = np.hypot(dst[:, 0] - src[:, 0], dst[:, 1] - src[:, 1])
        if point_clearance is None:
            ok = np.zeros(len(allc), dtype=bool)
        else:
            ends = np.minimum(np.repeat(np.asarray(point_clearance, float), counts),
                              self.node_clearance[allc])
            ok = ends - 0.5 * lens >= thr
        todo = np.flatnonzero(~ok)
        ok[todo] = clear_segments(g, (W, H), src[todo], dst[todo], thr[todo])
        # each point's kept links: consecutive pieces of the kept ones (views of them)
        ids, ln = allc[ok], lens[ok]
        e = np.concatenate([[0], np.cumsum(ok)])[np.cumsum([0] + counts)].tolist()
        return [(ids[a:b], ln[a:b]) for a, b in zip(e[:-1], e[1:], strict=True)]

    def field(self, seeds: np.ndarray, seed_cost: np.ndarray, key: Any = None) -> np.ndarray:
        """Lattice distance (V,) from the seed set (cached by ``key`` when given)."""
        if key is not None:
            hit = self._fields.get(key)
            if hit is not None:
                self._fields.move_to_end(key)
                return hit
        d = _dijkstra(self.nbr, self.dlen, np.asarray(seeds, dtype=np.int64),
                      np.asarray(seed_cost, dtype=float))
        d.setflags(write=False)
        if key is not None:
            self._fields[key] = d
            while len(self._fields) > _FIELD_CACHE_SIZE:
                self._fields.popitem(last=False)
        return d


@nb.njit(cache=True)
def _any_node_near(pts: np.ndarray, radius: float, L: float, oa: int, ob: int,
                   ids: np.ndarray, coords: np.ndarray) -> np.ndarray:
    """:meth:`Lattice.any_node_near`: the window of ``Lattice.nodes_near_all`` (span x
    span lattice indices from the floor of the point less the radius), a node within
    ``radius + 1e-12`` found in it."""
    nb_, na = ids.shape
    span = int(math.ceil(2 * radius / L)) + 2
    out = np.zeros(pts.shape[0], np.bool_)
    for k in range(pts.shape[0]):
        px, py = pts[k, 0], pts[k, 1]
        a0 = int(math.floor((px - radius) / L)) - oa
        b0 = int(math.floor((py - radius) / L)) - ob
        for db in range(span):
            b = b0 + db
            if b < 0 or b >= nb_:
                continue
            for da in range(span):
                a = a0 + da
                if a < 0 or a >= na or ids[b, a] < 0:
                    continue
                v = ids[b, a]
                if math.hypot(coords[v, 0] - px, coords[v, 1] - py) <= radius + 1e-12:
                    out[k] = True
                    break
            if out[k]:
                break
    return out


def clear_segments(geometry: Any, workspace: tuple[float, float], a: np.ndarray,
                   b: np.ndarray, need: np.ndarray) -> np.ndarray:
    """Whether each straight segment ``a[k] -> b[k]`` keeps an exact clearance of at least
    ``need[k] - 1e-12`` (``need > 0``) from the obstacles of ``geometry`` (a
    ``GeometrySet``) and the workspace border: a few among few obstacles
    (:data:`FEW_PAIRS`) against all obstacles at once, more against the obstacles near
    each one only (the bucket grid of
    :mod:`lamp.mrmp.obstacle_grid`: the same decisions as against all of them)."""
    W, H = workspace
    ok = np.zeros(len(a), dtype=bool)
    if len(a) == 0:
        return ok
    n_obstacles = len(geometry.circles) + max(0, len(geometry.ptr) - 1)
    if len(a) <= FEW and len(a) * n_obstacles <= FEW_PAIRS:  # against all at once
        g = geometry
        return segments_clearance(np.ascontiguousarray(a), np.ascontiguousarray(b), g.circles,
                                  g.verts, g.ptr, W, H) >= need - 1e-12
    grid = get_grid(geometry)
    return grid_clear_segments(np.ascontiguousarray(a, dtype=np.float64),
                               np.ascontiguousarray(b, dtype=np.float64),
                               np.ascontiguousarray(need, dtype=np.float64),
                               geometry.circles, geometry.verts, geometry.ptr, float(W),
                               float(H), grid.ptr, grid.idx, grid.box, grid.nx, grid.ny,
                               grid.cell)


def get_lattice(space: RobotSpace, step: float = 0.05) -> Lattice:
    """The lattice of ``space`` with ``step`` (built once per space and step)."""
    key = ("lattice", float(step))
    lat = space.derived.get(key)
    if lat is None:
        lat = Lattice(space, step)
        space.derived[key] = lat
    return lat
