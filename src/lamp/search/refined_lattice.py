"""The object lattice refined off-grid in narrow passages (continuous refinement).

``RefinedLattice`` is an :class:`~lamp.search.lattice.ObjectLattice` that can add extra
vertices: poses off the lattice (``lamp.search.narrow.narrow_poses``: corridor centrelines
with the object aligned to them) joined to each other and to nearby lattice nodes by
checked straight motions within the model's range. The lattice stays coarse in the open;
only where it cannot pass does the search get the finer poses. Until :meth:`refine` adds
any, the refined lattice is exactly the lattice (same ids, edges, costs).

Extra vertices get the ids ``n_nodes, n_nodes + 1, ...``; every method of the lattice
(``pose``, ``successors``, ``heuristic``, ``start_connections``, ...) accepts them. An
edge to or from an extra vertex is valid when ``ObjectSpace.motions_free`` or, where the
grid's conservative answer is "not free", ``ExactSpace.motion_free`` says so (checked
lazily: :meth:`refine` proposes each vertex's links, and all the links of a vertex are
checked together when it is first asked for, so the graph does not depend on the order of
the questions: ``tests/test_narrow.py``); it costs the
lattice's metric (``distance``) plus ``EDGE_OVERHEAD``, so the heuristic stays admissible
and consistent, and chains of short refined edges are not preferred to the coarse lattice.
Where the object is tight (less exact clearance than ``LINK_CLEARANCE`` at either end) an
edge that joins the lattice, or turns the object by more than ``TIGHT_TURN``, costs
``TIGHT_LINK_COST`` more (also from a start off the graph, ``start_connections``): the
search turns the object in the open and enters a passage straight. Costs only grow, so
the heuristic stays admissible.
"""

from __future__ import annotations

import math
from array import array
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from lamp.geometry import se2
from lamp.geometry.exact_space import ExactSpace
from lamp.search.lattice import Node, ObjectLattice, VirtualNode
from lamp.search.narrow import NarrowParams, narrow_poses

#: Added to the metric cost of every edge that touches an extra vertex (m).
EDGE_OVERHEAD = 0.01
#: Margin (m) around the object's pose and its goal of the window searched for passages.
REFINE_MARGIN = 3.0
#: Lattice nodes an extra vertex is joined to, at most (the nearest).
MAX_LATTICE_LINKS = 8
#: An extra vertex with less exact clearance than this (m) is joined to lattice nodes at
#: ``TIGHT_LINK_COST`` (m) more than the metric: turning onto the lattice in a passage is
#: allowed, but the search prefers to do it in the open.
LINK_CLEARANCE = 0.03
TIGHT_LINK_COST = 1.0
#: An edge to an extra vertex (from another, or from a start off the graph) that turns the
#: object by more than this (rad) while either end has less exact clearance than
#: ``LINK_CLEARANCE`` also costs
#: ``TIGHT_LINK_COST`` more: a turning push in a passage's mouth catches a corner and turns
#: the object the wrong way (corridor-08, seed 1: planned 2.33 -> 2.51 rad at 9 mm of
#: clearance, reached 2.06, then wedged), so the search turns in the open and enters
#: straight (along the extension poses of ``narrow_poses``) whenever it can.
TIGHT_TURN = 0.02


class RefinedLattice(ObjectLattice):
    """An object lattice with off-grid vertices added where passages are narrow."""

    def __init__(self, *args: object, exact: ExactSpace | None = None,
                 **kwargs: object) -> None:
        """The lattice's arguments, and optionally the exact twin of its space to use
        (default: one built on first use)."""
        super().__init__(*args, **kwargs)
        self._extra = np.zeros((0, 3))
        #: exact clearance (m) of each extra vertex
        self._clearance = np.zeros(0)
        #: each vertex's candidate links (ids, packed: a large window proposes some 10^5)
        #: in the order they were proposed; a link is checked when one of its ends is
        #: first asked for
        self._cand: dict[Node, array] = {}
        #: each link: the vertex whose pose it starts from, its other end, its extra cost
        self._from, self._to, self._extra_cost = array("q"), array("q"), array("d")
        #: each link's cost once checked (``math.inf``: not free; NaN: not checked yet)
        self._cost = array("d")
        self._tree: cKDTree | None = None
        self._exact = exact
        self._windows: list[tuple[float, float, float, float]] = []
        #: statistics: exact motion checks made for refined edges
        self.n_exact_checks = 0

    # -------------------------------------------------------------- extra ids
    @property
    def n_extra(self) -> int:
        return len(self._extra)

    @property
    def exact(self) -> ExactSpace:
        if self._exact is None:
            self._exact = ExactSpace.from_space(self.space)
        return self._exact

    def is_node(self, u: object) -> bool:
        return isinstance(u, (int, np.integer)) and 0 <= u < self.n_nodes + len(self._extra)

    def pose(self, u: Node | VirtualNode) -> np.ndarray:
        if isinstance(u, (int, np.integer)) and u >= self.n_nodes:
            return self._extra[int(u) - self.n_nodes].copy()
        return super().pose(u)

    def poses(self, nodes: Sequence[Node] | np.ndarray) -> np.ndarray:
        ids = np.asarray(nodes, dtype=np.int64)
        extra = ids >= self.n_nodes
        if not extra.any():
            return super().poses(ids)
        out = np.empty(ids.shape + (3,))
        out[~extra] = super().poses(ids[~extra])
        out[extra] = self._extra[ids[extra] - self.n_nodes]
        return out

    def _xyt(self, u: Node | VirtualNode) -> tuple[float, float, float]:
        if isinstance(u, (int, np.integer)) and u >= self.n_nodes:
            x, y, t = self._extra[int(u) - self.n_nodes]
            return float(x), float(y), float(t)
        return super()._xyt(u)

    def _pot(self, u: Node | VirtualNode, x: float, y: float) -> float:
        if isinstance(u, (int, np.integer)) and u >= self.n_nodes:  # off the grid: a pose
            return self.potential.at(x, y)  # type: ignore[union-attr]
        return super()._pot(u, x, y)

    def successors(self, u: Node) -> list[tuple[Node, float]]:
        if u >= self.n_nodes:
            return self._free_of(u)
        base = super().successors(u)
        more = self._free_of(u) if u in self._cand else None
        return base + more if more else base

    def _free_of(self, u: Node) -> list[tuple[Node, float]]:
        """``u``'s free links to and from extra vertices, as ``(other end, cost)`` in the
        order they were proposed; the links not checked yet are checked now, together."""
        cand = self._cand.get(u)
        if not cand:
            return []
        cost, a, b = self._cost, self._from, self._to
        todo = [k for k in cand if math.isnan(cost[k])]
        if todo:
            self._check_links(todo)
        return [(b[k] if a[k] == u else a[k], c) for k in cand if (c := cost[k]) != math.inf]

    def _check_links(self, ids: list[int]) -> None:
        """Check links ``ids`` (:meth:`_motions_free`) and cost the free ones."""
        us, vs = [self._from[k] for k in ids], [self._to[k] for k in ids]
        free = self._motions_free(self.poses(us), self.poses(vs))
        for k, u, v, f in zip(ids, us, vs, free, strict=True):
            self._cost[k] = (float(self.distance(self.pose(u), self.pose(v))) + EDGE_OVERHEAD
                             + self._extra_cost[k]) if f else math.inf

    def nearest_nodes(self, pose: ArrayLike, max_dist: float,
                      valid_only: bool = True) -> list[tuple[Node, float]]:
        out = super().nearest_nodes(pose, max_dist, valid_only)
        if self._tree is not None:
            p = np.asarray(pose, dtype=float)
            idx = self._tree.query_ball_point(p[:2], max_dist)
            for i in idx:
                d = float(self.distance(p, self._extra[i]))
                if d <= max_dist:
                    out.append((self.n_nodes + int(i), d))
            out.sort(key=lambda r: r[1])
        return out

    def start_connections(self, pose: ArrayLike, tolerance: float = 0.0
                          ) -> list[tuple[Node, float]]:
        out = super().start_connections(pose, tolerance)
        if self._tree is None:
            return out
        p = np.asarray(pose, dtype=float)
        idx = [int(i) for i in self._tree.query_ball_point(p[:2], self.max_translation * math.sqrt(2.0))]
        if not idx:
            return out
        targets = self._extra[idx]
        ok = np.asarray(self.in_model_range(p, targets), dtype=bool).reshape(-1)
        idx = [i for i, k in zip(idx, ok, strict=True) if k]
        links = self._free_links(p, [self.n_nodes + i for i in idx], tolerance)
        start_tight = float(self.exact.clearance(p)) < LINK_CLEARANCE if links else False
        out.extend((v, float(self.distance(p, self.pose(v))) + EDGE_OVERHEAD
                    + self._turn_cost(p, v, start_tight)) for v in links)
        out.sort(key=lambda r: r[1])
        return out

    # -------------------------------------------------------------- refinement
    def _free_links(self, p: np.ndarray, nodes: list[Node], tolerance: float = 0.0) -> list[Node]:
        """The ``nodes`` reachable from pose ``p`` by a free straight motion: the grid's
        answer first, the exact checker's where the grid says no (tolerance 0 only)."""
        if not nodes:
            return []
        targets = self.poses(nodes)
        free = self._motions_free(np.broadcast_to(p, targets.shape), targets, tolerance)
        return [v for v, f in zip(nodes, free, strict=True) if f]

    def _motions_free(self, starts: np.ndarray, ends: np.ndarray,
                      tolerance: float = 0.0) -> list[bool]:
        """Whether each straight motion ``starts[m] -> ends[m]`` is free: the grid's answer
        first, the exact checker's where the grid says no (tolerance 0 only)."""
        free = self.tolerant_space(tolerance).motions_free(starts, ends)
        self.n_motion_checks += len(free)
        out = []
        for f, p, q in zip(free, starts, ends, strict=True):
            if not f and tolerance == 0.0:
                self.n_exact_checks += 1
                f = self.exact.motion_free(p, q)
            out.append(bool(f))
        return out

    def refine(self, around: ArrayLike, params: NarrowParams | None = None) -> int:
        """Add the narrow-passage poses of a window around ``around`` and the goal with
        their edges; returns how many vertices were added (0 when the window is already
        covered). The window's margin is ``REFINE_MARGIN`` and doubles with every call,
        so repeated calls end up covering the whole map."""
        p = np.asarray(around, dtype=float)
        w, h = self.space.workspace
        g = self.anchor
        # each call searches a larger window (the route may leave the first one), until
        # one covers the whole map
        m = REFINE_MARGIN * 2.0 ** len(self._windows)
        window = (max(0.0, min(p[0], g[0]) - m), max(0.0, min(p[1], g[1]) - m),
                  min(w, max(p[0], g[0]) + m), min(h, max(p[1], g[1]) + m))
        if any(a[0] <= window[0] and a[1] <= window[1] and a[2] >= window[2] and a[3] >= window[3]
               for a in self._windows):
            return 0
        self._windows.append(window)
        new = narrow_poses(self.space, self.exact, window, params or NarrowParams(),
                           self._circle_headings(p))
        if len(self._extra) and len(new):  # drop poses already present
            d, _ = cKDTree(self._extra[:, :2]).query(new[:, :2])
            new = new[d > 1e-6]
        if len(new) == 0:
            return 0
        first = self.n_nodes + len(self._extra)
        self._extra = np.concatenate([self._extra, new])
        self._clearance = np.concatenate(
            [self._clearance, [float(self.exact.clearance(q)) for q in new]])
        self._tree = cKDTree(self._extra[:, :2])
        reach = self.max_translation * math.sqrt(2.0)
        for i in range(len(new)):
            u = first + i
            q = self._extra[u - self.n_nodes]
            # extra <-> extra (each pair once, from its lower id)
            cand = [self.n_nodes + int(j) for j in self._tree.query_ball_point(q[:2], reach)
                    if self.n_nodes + int(j) != u]
            cand = [v for v in cand if v < first or v > u]
            tight = self._clearance[u - self.n_nodes] < LINK_CLEARANCE
            if cand:
                ok = np.asarray(self.in_model_range(q, self.poses(cand)), dtype=bool).reshape(-1)
                for v in [v for v, k in zip(cand, ok, strict=True) if k]:
                    self._propose(u, v, self._turn_cost(q, v, tight))
            # extra <-> lattice; where the object is still in the passage such a link costs
            # TIGHT_LINK_COST more, so that it turns onto (or off) the lattice in the open
            # and enters the passage straight whenever it can
            nodes = self._candidates(q, reach, math.ceil(self.max_rotation / self.dtheta))
            extra_cost = TIGHT_LINK_COST if tight else 0.0
            if len(nodes):
                nodes = nodes[np.asarray(self.in_model_range(q, super().poses(nodes)), bool)]
                nodes = nodes[self._free_nodes(nodes)]
                order = np.argsort(self.distance(q, super().poses(nodes)), kind="stable")
                for v in nodes[order][:MAX_LATTICE_LINKS]:
                    self._propose(u, int(v), extra_cost)
        return len(new)

    def _turn_cost(self, q: np.ndarray, v: Node, q_tight: bool) -> float:
        """``TIGHT_LINK_COST`` for a motion from pose ``q`` to extra vertex ``v`` that turns
        by more than ``TIGHT_TURN`` where either end is tight (``q_tight``, or ``v``'s
        clearance below ``LINK_CLEARANCE``), else 0."""
        i = int(v) - self.n_nodes
        turn = abs(float(se2.wrap_angle(self._extra[i][2] - q[2])))
        pinched = q_tight or self._clearance[i] < LINK_CLEARANCE
        return TIGHT_LINK_COST if pinched and turn > TIGHT_TURN else 0.0

    def _circle_headings(self, around: np.ndarray) -> np.ndarray:
        """The headings a circle's passage poses take (any heading fits a circle): the
        lattice headings next to the goal's and, when ``around`` is a pose, next to its
        heading, so that the circle passes at the heading it comes with and leaves at
        the goal's, without turning in the passage (its pushes turn it only by drift)."""
        steps = {-1, 0, 1}
        if around.size == 3:
            k = round(float(se2.wrap_angle(around[2] - self.anchor[2])) / self.dtheta)
            steps |= {k - 1, k, k + 1}
        ks = sorted({s % self.n_headings for s in steps})
        return self.anchor[2] + self.dtheta * np.array(ks, dtype=float)

    def _propose(self, u: Node, v: Node, extra: float = 0.0) -> None:
        """A candidate link between extra vertex ``u`` and ``v`` (the motion from ``u``'s
        pose), costing ``extra`` more than the metric; checked when first asked for."""
        k = len(self._cost)
        self._from.append(u)
        self._to.append(v)
        self._extra_cost.append(extra)
        self._cost.append(math.nan)
        for end in (u, v):
            ids = self._cand.get(end)
            if ids is None:
                ids = self._cand[end] = array("q")
            ids.append(k)
