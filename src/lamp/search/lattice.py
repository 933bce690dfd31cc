"""SE(2) lattice of object poses anchored at one pose (the goal for LAMP, the start for GCo).

Nodes are the poses ``anchor_xy + step * (i, j)`` (world axes) with headings
``anchor_theta + k * 2 pi / n_headings``, restricted to positions inside the workspace.
Because LAMP anchors the lattice at the object's goal pose, the goal is a node and every
lattice path ends exactly on it.

Node ids are flat Python ints ``(ii * n_j + jj) * n_headings + k`` with ``ii = i - i_min``
and ``jj = j - j_min`` (cheap to hash and to store in arrays). Virtual nodes for a
continuous pose (the current, drifted pose of the object) are plain ``(x, y, theta)``
tuples; :meth:`ObjectLattice.heuristic` accepts both.

Motion primitives (26, ``PRIMITIVES``), as lattice offsets ``(di, dj, dk)``: the 8
translations ``(di, dj) in {-1, 0, 1}^2 \\ {(0, 0)}`` (axis steps of ``step``, diagonals of
``step * sqrt(2)``), each with a heading change ``dk in {-1, 0, +1}`` bins (24), and the 2
pure rotations ``(0, 0, +-1)``.

The same set is GCo's "8 neighbours or stay, times rotation {0, +-1}, minus stay". A
primitive moves the object along ``se2.interpolate`` (translation and rotation blended
linearly), which is the object motion the manipulation model is asked for. With the
defaults (0.1 m, 16 headings = 0.39 rad) every primitive lies in the model's trained range
(|dx|, |dy| <= 0.2 m in the object frame, |dtheta| <= 0.5 rad); the constructor checks it.

Edge cost = translation length + ``w_rot * |dtheta|`` (:func:`motion_cost`, the cost of any
straight motion: lattice primitives and the motions that join a continuous pose to the
lattice alike). The default ``w_rot`` is the object's bounding radius (m/rad), so a
rotation costs the arc length travelled by the object's farthest point: rotating a large
object is as expensive as the sweep it causes.

The heuristic and :meth:`ObjectLattice.distance` are the lattice metric of
:mod:`lamp.search.metric` (the octile norm of the translation, strengthened by a landmark
potential when the lattice has a ``landmark``, plus ``w_rot * |wrap(dtheta)|``): equal to
every primitive's cost, with the triangle inequality between any poses, hence admissible
and consistent on every lattice edge; see that module for the guarantees and for how D*
Lite stays consistent on the (cheaper) joining motions.

A node is valid when its pose is free (``ObjectSpace.pose_free``); an edge is valid when
both ends are valid and its swept motion is free (``ObjectSpace.motions_free``). Both are
computed lazily, in batches of one node's 26 primitives, and cached in one packed store
(:mod:`lamp.search.lattice_primitives`: 4 bytes hold a node's state and its edges').
Edge validity is symmetric (the reverse motion sweeps the same set), so each motion is
checked once, from the lower node id, and kept once.

Continuous poses join the lattice through :meth:`start_connections` (one free straight
motion to a node within the model's range, costed by :func:`motion_cost`); the goal node
is among them whenever it is within range, which gives the final approach to the exact
goal pose for free.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from lamp.contract.model import MOTION_RANGE
from lamp.geometry import se2
from lamp.geometry.distance_tiles import lazy_zeros
from lamp.geometry.object_space import ObjectSpace
from lamp.scene.model import Scene
from lamp.search.landmark import LandmarkPotential
from lamp.search.lattice_primitives import (
    BLOCKED,
    FREE,
    PRIMITIVES,
    SLOT,
    STORE_DTYPE,
    UNKNOWN,
    check_lattice_args,
    edge_words,
    node_words,
    primitive_costs,
    successor_kernel,
)
from lamp.search.metric import OCTILE_MINOR, TWO_PI, lattice_metric, motion_cost

Node = int
VirtualNode = tuple[float, float, float]

#: Successor lists a lattice keeps by default (~1.5 kB a node).
SUCC_KEPT = 20_000

#: the manipulation model's trained range (object frame): |dx|, |dy| and |dtheta|
MODEL_MAX_TRANSLATION = MOTION_RANGE[0]
MODEL_MAX_ROTATION = MOTION_RANGE[2]


class ObjectLattice:
    """Lazily collision-checked SE(2) lattice over one :class:`ObjectSpace`.

    Args:
        space: collision queries for the object (its inflation is the lattice's).
        anchor: the pose that is node ``(0, 0, 0)`` (LAMP: the goal).
        step: translation step (m).
        n_headings: number of heading bins over 2 pi.
        w_rot: rotation cost weight (m/rad); default: the object's bounding radius.
        max_translation, max_rotation: the model's range; primitives and start
            connections stay within it (|dx|, |dy| <= max_translation in the object frame,
            |dtheta| <= max_rotation).
        landmark: (x, y) of a landmark (LAMP: the object's start); the metric then also
            bounds the translation by the landmark potential (:mod:`lamp.search.landmark`),
            which sees the detours obstacles force. None: the octile metric alone.
        succ_kept: successor lists kept (speed only: a dropped one is rebuilt the same); 0: none.
    """

    def __init__(
        self,
        space: ObjectSpace,
        anchor: ArrayLike,
        step: float = 0.1,
        n_headings: int = 16,
        w_rot: float | None = None,
        max_translation: float = MODEL_MAX_TRANSLATION,
        max_rotation: float = MODEL_MAX_ROTATION,
        landmark: ArrayLike | None = None,
        succ_kept: int = SUCC_KEPT,
    ) -> None:
        anchor, w_rot, dtheta = check_lattice_args(space, anchor, step, n_headings, w_rot,
                                                   max_translation, max_rotation, succ_kept)
        self.space = space
        self.anchor = anchor.copy()
        self.anchor[2] = se2.wrap_angle(anchor[2])
        self.step = float(step)
        self.n_headings = int(n_headings)
        self.dtheta = dtheta
        self.w_rot = float(w_rot)
        self.max_translation = float(max_translation)
        self.max_rotation = float(max_rotation)

        w, h = space.workspace
        ax, ay = self.anchor[0], self.anchor[1]
        eps = 1e-9
        self.i_min = math.ceil(-ax / step - eps)
        self.i_max = math.floor((w - ax) / step + eps)
        self.j_min = math.ceil(-ay / step - eps)
        self.j_max = math.floor((h - ay) / step + eps)
        self.n_i = max(0, self.i_max - self.i_min + 1)
        self.n_j = max(0, self.j_max - self.j_min + 1)
        if self.n_i == 0 or self.n_j == 0:
            raise ValueError(
                f"anchor {anchor.tolist()} gives an empty lattice in {space.workspace}"
            )
        self.n_nodes = self.n_i * self.n_j * self.n_headings
        #: id of the anchor pose (LAMP: the goal node)
        self.anchor_node: Node = self.node_id(0, 0, 0)

        self._prim, self._prim_cost, self._prim_reach = primitive_costs(step, self.w_rot, dtheta)
        self._prim_cost_list = self._prim_cost.tolist()
        self._slot = np.array(SLOT, dtype=np.int64)
        self._out_ids = np.empty(len(PRIMITIVES), dtype=np.int64)
        self._out_prim = np.empty(len(PRIMITIVES), dtype=np.int64)
        # zero-filled (UNKNOWN) in small pages: memory grows with the part of the map the
        # search visits (``np.zeros`` asks for huge pages: a node looked at, 2 MB resident)
        self._store = lazy_zeros((edge_words(self.n_i, self.n_j, self.n_headings),),
                                 STORE_DTYPE)
        self._succ: dict[Node, list[tuple[Node, float]]] = {}
        self._succ_kept = int(succ_kept)
        self._tolerant: dict[float, ObjectSpace] = {}
        #: statistics: poses and motions checked so far
        self.n_pose_checks = 0
        self.n_motion_checks = 0
        if landmark is not None:
            landmark = np.asarray(landmark, dtype=float).reshape(-1)[:2]
            if landmark.shape != (2,) or not np.all(np.isfinite(landmark)):
                raise ValueError(f"landmark must be a finite (x, y), got {landmark!r}")
        self.landmark = None if landmark is None else (float(landmark[0]), float(landmark[1]))
        self._potential: LandmarkPotential | None = None
        self._pot_values: memoryview | None = None

    @classmethod
    def from_scene(
        cls,
        scene: Scene,
        object_index: int,
        object_poses: ArrayLike | None = None,
        inflation: float = 0.0,
        **kwargs: float,
    ) -> ObjectLattice:
        """LAMP's lattice for ``scene.objects[object_index]``, anchored at its goal, with the
        scene's obstacles and the other objects (at ``object_poses``) as obstacles."""
        space = ObjectSpace.from_scene(scene, object_index, object_poses, inflation)
        return cls(space, scene.objects[object_index].goal, **kwargs)

    @property
    def goal_node(self) -> Node:
        """The anchor's id: the goal node of a lattice anchored at the goal (LAMP)."""
        return self.anchor_node

    # ------------------------------------------------------------------ ids
    def node_id(self, i: int, j: int, k: int) -> Node:
        """Flat id of lattice offset (i, j, k) from the anchor (k taken modulo n_headings)."""
        ii, jj = i - self.i_min, j - self.j_min
        if not (0 <= ii < self.n_i and 0 <= jj < self.n_j):
            raise ValueError(f"lattice offset ({i}, {j}) lies outside the workspace")
        return (ii * self.n_j + jj) * self.n_headings + (k % self.n_headings)

    def ijk(self, u: Node) -> tuple[int, int, int]:
        """Lattice offset (i, j, k) of node ``u`` (inverse of :meth:`node_id`)."""
        rest, k = divmod(int(u), self.n_headings)
        ii, jj = divmod(rest, self.n_j)
        return ii + self.i_min, jj + self.j_min, k

    def is_node(self, u: object) -> bool:
        return isinstance(u, (int, np.integer)) and 0 <= u < self.n_nodes

    def pose(self, u: Node | VirtualNode) -> np.ndarray:
        """(3,) pose of a node (a virtual node is its own pose)."""
        if not isinstance(u, (int, np.integer)):
            return np.asarray(u, dtype=float)
        i, j, k = self.ijk(u)
        return np.array(
            [
                self.anchor[0] + i * self.step,
                self.anchor[1] + j * self.step,
                se2.wrap_angle(self.anchor[2] + k * self.dtheta),
            ]
        )

    def poses(self, nodes: Sequence[Node] | np.ndarray) -> np.ndarray:
        """(N, 3) poses of node ids (vectorised)."""
        x, y, th = self._decode(np.asarray(nodes, dtype=np.int64))
        th = se2.wrap_angle(th)
        return np.stack([x, y, np.asarray(th, dtype=float).reshape(x.shape)], axis=-1)

    def _decode(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x, y and the *unwrapped* heading of int64 node ids (vectorised)."""
        rest, k = np.divmod(u, self.n_headings)
        ii, jj = np.divmod(rest, self.n_j)
        return (
            self.anchor[0] + (ii + self.i_min) * self.step,
            self.anchor[1] + (jj + self.j_min) * self.step,
            self.anchor[2] + k * self.dtheta,
        )

    def _xyt(self, u: Node | VirtualNode) -> tuple[float, float, float]:
        if isinstance(u, (int, np.integer)):
            rest, k = divmod(int(u), self.n_headings)
            ii, jj = divmod(rest, self.n_j)
            return (
                self.anchor[0] + (ii + self.i_min) * self.step,
                self.anchor[1] + (jj + self.j_min) * self.step,
                self.anchor[2] + k * self.dtheta,
            )
        return float(u[0]), float(u[1]), float(u[2])

    # ------------------------------------------------------------ validity
    def _free_nodes(self, nodes: np.ndarray) -> np.ndarray:
        """Which of the int64 node ids are free (checked where not known yet)."""
        words = node_words(nodes, self.n_j, self.n_headings)
        unknown = np.unique(nodes[self._store[words] & 3 == UNKNOWN])
        if len(unknown):
            state = BLOCKED + self.space.pose_free(self.poses(unknown))
            self._store[node_words(unknown, self.n_j, self.n_headings)] |= state.astype(
                STORE_DTYPE)
            self.n_pose_checks += len(unknown)
        return self._store[words] & 3 == FREE

    def node_valid(self, u: Node) -> bool:
        """Whether the node's pose is free (cached)."""
        return bool(self._free_nodes(np.array([u], dtype=np.int64))[0])

    def validate_all_nodes(self) -> np.ndarray:
        """Check every node at once (one batch) and return the (n_nodes,) validity mask."""
        return self._free_nodes(np.arange(self.n_nodes, dtype=np.int64))

    def _neighbours(self, u: Node) -> tuple[np.ndarray, np.ndarray]:
        """(primitive indices, neighbour ids) of the primitives from ``u`` that stay on the grid."""
        rest, k = divmod(int(u), self.n_headings)
        ii, jj = divmod(rest, self.n_j)
        p = self._prim
        ni = ii + p[:, 0]
        nj = jj + p[:, 1]
        ok = (ni >= 0) & (ni < self.n_i) & (nj >= 0) & (nj < self.n_j)
        idx = np.nonzero(ok)[0]
        nk = (k + p[idx, 2]) % self.n_headings
        return idx, (ni[idx] * self.n_j + nj[idx]) * self.n_headings + nk

    def successors(self, u: Node) -> list[tuple[Node, float]]:
        """Valid out-edges ``[(v, cost)]`` of node ``u`` (empty when ``u`` is invalid)."""
        cached = self._succ.get(u)
        if cached is not None:
            return cached
        if self.space.grid.capped:
            x, y, _ = self._xyt(u)
            self.space.prepare_point(x, y, self._prim_reach)
        n, n_pose, n_motion = successor_kernel(
            int(u), self.n_i, self.n_j, self.n_headings, self.i_min, self.j_min,
            self.anchor[0], self.anchor[1], self.anchor[2], self.step, self.dtheta,
            self._prim, self._slot, self._store,
            self._out_ids, self._out_prim, *self.space.kernel_args,
        )  # fmt: skip
        self.n_pose_checks += n_pose
        self.n_motion_checks += n_motion
        cost = self._prim_cost_list
        ids = self._out_ids[:n].tolist()
        out = list(zip(ids, [cost[p] for p in self._out_prim[:n].tolist()], strict=True))
        if self._succ_kept:
            if len(self._succ) >= self._succ_kept:
                self._succ.clear()  # recomputing from the validity caches is cheap
            self._succ[u] = out
        return out

    def predecessors(self, v: Node) -> list[tuple[Node, float]]:
        """Valid in-edges ``[(u, cost(u, v))]``; the primitive set is closed under reversal
        and edge validity and cost are symmetric, so these are the successors."""
        return self.successors(v)

    def cost(self, u: Node, v: Node) -> float:
        """Cost of the lattice edge u -> v; ``inf`` when it is not a valid edge (or when
        ``u`` is not a lattice node, e.g. a virtual start)."""
        if not self.is_node(u):
            return math.inf
        return next((c for w, c in self.successors(u) if w == v), math.inf)

    def primitive(self, u: Node, v: Node) -> np.ndarray:
        """The object-frame motion (dx, dy, dtheta) from node/pose ``u`` to ``v``: the
        ``m_O`` of ``GetPrimitive`` in the paper's Alg. 2 (``se2.relative``)."""
        return se2.relative(self.pose(u), self.pose(v))

    # ----------------------------------------------------------- heuristic
    @property
    def potential(self) -> LandmarkPotential | None:
        """The landmark potential (:mod:`lamp.search.landmark`) over this lattice's
        positions, built on first use; None without a landmark."""
        if self._potential is None and self.landmark is not None:
            self._potential = LandmarkPotential(
                self.space,
                (self.anchor[0] + self.i_min * self.step, self.anchor[1] + self.j_min * self.step),
                self.step, (self.n_i, self.n_j), self.landmark,
                radius=self.max_translation * math.sqrt(2.0),
            )
            # indexed per heuristic call: plain floats, read in place (no copy of the
            # whole map's values)
            self._pot_values = memoryview(np.ascontiguousarray(self._potential.values,
                                                               dtype=np.float64))
        return self._potential

    def _pot(self, u: Node | VirtualNode, x: float, y: float) -> float:
        """The landmark potential of a node (its position's value) or of a pose."""
        if isinstance(u, (int, np.integer)):
            return self._pot_values[int(u) // self.n_headings]  # type: ignore[index]
        return self.potential.at(x, y)  # type: ignore[union-attr]

    def potentials(self, poses: ArrayLike) -> np.ndarray:
        """(...,) landmark potentials of (..., 3) poses (zeros without a landmark)."""
        p = np.asarray(poses, dtype=float)
        if self.potential is None:
            return np.zeros(p.shape[:-1])
        flat = p.reshape(-1, 3)
        at = self.potential.at
        return np.array([at(float(x), float(y)) for x, y in flat[:, :2]]).reshape(p.shape[:-1])

    def heuristic(self, u: Node | VirtualNode, v: Node | VirtualNode) -> float:
        """:func:`lattice_metric` between nodes or poses: a lower bound of every path cost
        from ``u`` to ``v``, consistent on every edge, with the triangle inequality (scalar
        fast path of the same formula; equal to :meth:`distance`)."""
        ax, ay, at = self._xyt(u)
        bx, by, bt = self._xyt(v)
        dx, dy = abs(ax - bx), abs(ay - by)
        d = abs(at - bt) % TWO_PI
        if dx < dy:
            dx, dy = dy, dx
        t = dx + OCTILE_MINOR * dy
        if self.landmark is not None:
            if self._pot_values is None:
                self.potential  # noqa: B018 (builds it)
            dp = abs(self._pot(u, ax, ay) - self._pot(v, bx, by))
            if dp > t:
                t = dp
        return t + self.w_rot * min(d, TWO_PI - d)

    def distance(self, a: ArrayLike, b: ArrayLike) -> np.ndarray | float:
        """:func:`lattice_metric` between (..., 3) poses (vectorised)."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        dpot = 0.0 if self.landmark is None else self.potentials(a) - self.potentials(b)
        return lattice_metric(
            a[..., 0] - b[..., 0], a[..., 1] - b[..., 1], a[..., 2] - b[..., 2], self.w_rot, dpot
        )

    # ---------------------------------------------------- continuous poses
    def _candidates(self, pose: np.ndarray, radius: float, max_dk: int) -> np.ndarray:
        """Ids of nodes within ``radius`` (translation) and ``max_dk`` heading bins of pose."""
        fi = (pose[0] - self.anchor[0]) / self.step
        fj = (pose[1] - self.anchor[1]) / self.step
        r = radius / self.step
        i0 = max(self.i_min, math.floor(fi - r))
        i1 = min(self.i_max, math.ceil(fi + r))
        j0 = max(self.j_min, math.floor(fj - r))
        j1 = min(self.j_max, math.ceil(fj + r))
        if i1 < i0 or j1 < j0:
            return np.zeros(0, dtype=np.int64)
        fk = se2.wrap_angle(pose[2] - self.anchor[2]) / self.dtheta
        k0 = math.floor(fk)
        if 2 * max_dk + 2 >= self.n_headings:
            ks = np.arange(self.n_headings)
        else:
            ks = np.unique(np.arange(k0 - max_dk, k0 + max_dk + 2) % self.n_headings)
        ii = np.arange(i0, i1 + 1) - self.i_min
        jj = np.arange(j0, j1 + 1) - self.j_min
        grid = (ii[:, None, None] * self.n_j + jj[None, :, None]) * self.n_headings + ks
        return grid.reshape(-1).astype(np.int64)

    def nearest_nodes(
        self, pose: ArrayLike, max_dist: float, valid_only: bool = True
    ) -> list[tuple[Node, float]]:
        """Nodes within ``max_dist`` of ``pose`` in the heuristic's metric, nearest first,
        as ``[(node, distance)]`` (only free nodes unless ``valid_only`` is False)."""
        pose = np.asarray(pose, dtype=float)
        max_dk = (
            self.n_headings if self.w_rot == 0 else math.ceil(max_dist / self.w_rot / self.dtheta)
        )
        cand = self._candidates(pose, max_dist, max_dk)
        if len(cand) == 0:
            return []
        d = self.distance(pose, self.poses(cand))
        keep = d <= max_dist
        cand, d = cand[keep], d[keep]
        if valid_only and len(cand):
            ok = self._free_nodes(cand)
            cand, d = cand[ok], d[ok]
        order = np.argsort(d, kind="stable")
        return [(int(cand[o]), float(d[o])) for o in order]

    def in_model_range(self, a: ArrayLike, b: ArrayLike) -> np.ndarray | bool:
        """Whether the motion a -> b (object frame) is within the model's trained range."""
        m = se2.relative(a, b)
        ok = (
            (np.abs(m[..., 0]) <= self.max_translation + 1e-9)
            & (np.abs(m[..., 1]) <= self.max_translation + 1e-9)
            & (np.abs(m[..., 2]) <= self.max_rotation + 1e-9)
        )
        return bool(ok) if np.ndim(ok) == 0 else ok

    def start_connections(
        self, pose: ArrayLike, tolerance: float = 0.0
    ) -> list[tuple[Node, float]]:
        """Nodes reachable from the continuous ``pose`` by one free straight motion within
        the model's range, as ``[(node, motion cost)]`` cheapest first.

        The planner treats ``pose`` as a virtual start node with these out-edges (see
        ``DStarLite.plan_shortest_path(start_edges=...)``). The goal node is included
        whenever it is within range, so a pose near the goal connects straight to it.
        ``tolerance > 0`` checks these connecting motions for the footprint shrunk by
        ``tolerance`` (use it when execution drift left the object touching an obstacle,
        closer than the collision checker's band, so that it can move away).
        """
        pose = np.asarray(pose, dtype=float)
        if pose.shape != (3,) or not np.all(np.isfinite(pose)):
            raise ValueError(f"pose must be a finite (x, y, theta), got {pose!r}")
        if tolerance < 0 or not math.isfinite(tolerance):
            raise ValueError(f"tolerance must be finite and >= 0, got {tolerance!r}")
        radius = self.max_translation * math.sqrt(2.0)
        cand = self._candidates(pose, radius, math.ceil(self.max_rotation / self.dtheta))
        if len(cand) == 0:
            return []
        targets = self.poses(cand)
        in_range = self.in_model_range(pose, targets)
        cand, targets = cand[in_range], targets[in_range]
        if len(cand) == 0:
            return []
        ok = self._free_nodes(cand)
        cand, targets = cand[ok], targets[ok]
        space = self.tolerant_space(tolerance)
        free = space.motions_free(np.broadcast_to(pose, targets.shape), targets)
        self.n_motion_checks += len(free)
        cand, targets = cand[free], targets[free]
        cost = motion_cost(pose, targets, self.w_rot)
        order = np.argsort(cost, kind="stable")
        return [(int(cand[o]), float(cost[o])) for o in order]

    def connection_cost(self, a: ArrayLike, b: ArrayLike, tolerance: float = 0.0) -> float | None:
        """Cost of the direct motion between two continuous poses (e.g. a drifted pose and
        the exact goal), or None when it leaves the model's range or is not free."""
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        if not self.in_model_range(a, b):
            return None
        if not self.tolerant_space(tolerance).motion_free(a, b):
            return None
        return float(motion_cost(a, b, self.w_rot))

    def tolerant_space(self, tolerance: float) -> ObjectSpace:
        """The object space with the footprint shrunk by ``tolerance`` (m; cached per value;
        ``ValueError`` when that would leave nothing of a thin object)."""
        if tolerance == 0.0:
            return self.space
        sp = self._tolerant.get(tolerance)
        if sp is None:
            sp = self.space.with_inflation(self.space.inflation - tolerance)
            self._tolerant[tolerance] = sp
        return sp

    def path_poses(self, path: Sequence[Node | VirtualNode]) -> np.ndarray:
        """(P, 3) poses of a path of nodes and virtual nodes."""
        return np.array([self.pose(u) for u in path], dtype=float).reshape(-1, 3)
