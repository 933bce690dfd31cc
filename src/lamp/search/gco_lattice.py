"""GCo's object-only planner: weighted A* (w = 2) on a 0.1 m / 0.1 rad lattice.

GCo (the LAMP paper's baseline) plans the object alone with weighted A*
on a lattice of 0.1 m and 0.1 rad with 26 moves (8 neighbours or stay, times rotation
{0, +-0.1}, minus staying put), inflating the object by 0.2 m in its collision check
(``gco-ori``) or not at all (``gco-var``). Our version:

* :class:`GCoLattice` is an :class:`ObjectLattice` anchored at the object's current pose
  with ``step = 0.1`` and ``n_headings = round(2 pi / 0.1) = 63`` (0.0997 rad, so the
  heading lattice closes on itself). Its 26 primitives are exactly GCo's moves.
* Nodes must be free for the inflated footprint and edges are checked as swept motions
  (stricter than checking end states only).
* The start pose is where the object is, so when it is not free for the *inflated*
  footprint (common with the 0.2 m buffer near obstacles) its out-edges are checked
  without inflation; their end nodes must still be free with inflation.
* The goal is a region: nodes within ``step`` and one heading bin of the goal pose from
  which the direct motion to the exact goal is free without inflation (the object must end
  on its goal whatever the buffer). The path returned ends on the exact goal pose. The
  heuristic is the Euclidean SE(2) metric (``hypot(dx, dy) + w_rot * |dtheta|``) to the
  goal minus the region's radius (admissible and consistent for the region).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Hashable

import numpy as np
from numpy.typing import ArrayLike

from lamp.geometry import se2
from lamp.geometry.object_space import ObjectSpace
from lamp.scene.model import Scene
from lamp.search.astar import AStarResult, weighted_astar
from lamp.search.lattice import Node, ObjectLattice

GCO_STEP = 0.1
GCO_ROT_STEP = 0.1
GCO_WEIGHT = 2.0
GCO_INFLATION_ORI = 0.2
GCO_INFLATION_VAR = 0.0


class GCoLattice(ObjectLattice):
    """GCo's object lattice, anchored at the start pose.

    Args:
        space: collision queries with GCo's inflation.
        start: the object's current pose (the anchor).
        step, rot_step: translation (m) and rotation (rad) resolution.
        exact_space: zero-inflation queries for leaving an inflated-invalid start and for
            the final motion onto the goal (default: ``space`` when its inflation is 0,
            otherwise built on demand).
    """

    def __init__(
        self,
        space: ObjectSpace,
        start: ArrayLike,
        step: float = GCO_STEP,
        rot_step: float = GCO_ROT_STEP,
        w_rot: float | None = None,
        exact_space: ObjectSpace | None = None,
    ) -> None:
        if not (rot_step > 0 and math.isfinite(rot_step)):
            raise ValueError(f"rot_step must be finite and > 0, got {rot_step!r}")
        n_headings = max(3, round(2.0 * math.pi / rot_step))
        super().__init__(space, start, step=step, n_headings=n_headings, w_rot=w_rot)
        self._exact = exact_space

    @property
    def exact_space(self) -> ObjectSpace:
        if self._exact is None:
            if self.space.inflation == 0.0:
                self._exact = self.space
            else:
                self._exact = self.space.with_inflation(0.0)
        return self._exact

    def successors(self, u: Node) -> list[tuple[Node, float]]:
        if u != self.anchor_node or self.node_valid(u):
            return super().successors(u)
        cached = self._succ.get(u)
        if cached is not None:
            return cached
        # the start is invalid for the inflated footprint: leave it without inflation
        idx, nbrs = self._neighbours(u)
        ok = self._free_nodes(nbrs)
        idx, nbrs = idx[ok], nbrs[ok]
        pu = self.pose(u)
        free = self.exact_space.motions_free(np.broadcast_to(pu, (len(nbrs), 3)), self.poses(nbrs))
        self.n_motion_checks += len(free)
        out = [
            (int(v), float(c)) for v, c in zip(nbrs[free], self._prim_cost[idx[free]], strict=True)
        ]
        self._succ[u] = out
        return out


_SPACE_CACHE: OrderedDict[tuple, ObjectSpace] = OrderedDict()
_SPACE_CACHE_SIZE = 16


def _cached_space(
    scene: Scene, object_index: int, poses: np.ndarray, inflation: float
) -> ObjectSpace:
    key = (scene, int(object_index), poses.round(9).tobytes(), float(inflation))
    sp = _SPACE_CACHE.get(key)
    if sp is None:
        sp = ObjectSpace.from_scene(scene, object_index, poses, inflation)
        _SPACE_CACHE[key] = sp
        if len(_SPACE_CACHE) > _SPACE_CACHE_SIZE:
            _SPACE_CACHE.popitem(last=False)
    else:
        _SPACE_CACHE.move_to_end(key)
    return sp


def gco_search(
    lattice: GCoLattice,
    goal: ArrayLike,
    weight: float = GCO_WEIGHT,
    max_expansions: int | None = 200_000,
    time_limit: float | None = None,
) -> tuple[np.ndarray | None, AStarResult]:
    """Weighted A* on ``lattice`` from its anchor to the goal region; returns the (P, 3)
    path (start pose, lattice poses, exact goal) or None, and the search result."""
    goal = np.asarray(goal, dtype=float)
    radius = lattice.step + lattice.w_rot * lattice.dtheta
    exact = lattice.exact_space
    goal_ok: dict[Hashable, bool] = {}

    def is_goal(v: Hashable) -> bool:
        ok = goal_ok.get(v)
        if ok is None:
            p = lattice.pose(v)
            dt, dr = se2.pose_distance(p, goal)
            ok = bool(
                dt <= lattice.step + 1e-9
                and dr <= lattice.dtheta + 1e-9
                and exact.motion_free(p, goal)
            )
            goal_ok[v] = ok
        return ok

    def heuristic(v: Hashable) -> float:
        # GCo's own Euclidean SE(2) metric (not the LAMP lattice's octile one): the
        # baseline's search is kept as published
        dt, dr = se2.pose_distance(lattice.pose(v), goal)
        return max(0.0, float(dt + lattice.w_rot * dr) - radius)

    res = weighted_astar(
        lattice,
        lattice.anchor_node,
        weight=weight,
        is_goal=is_goal,
        heuristic=heuristic,
        max_expansions=max_expansions,
        time_limit=time_limit,
    )
    if not res.success:
        return None, res
    poses = lattice.path_poses(res.path)
    if se2.pose_distance(poses[-1], goal)[0] > 1e-9 or se2.pose_distance(poses[-1], goal)[1] > 1e-9:
        poses = np.vstack([poses, goal[None, :]])
    return poses, res


def gco_object_path(
    scene: Scene,
    object_index: int,
    start_pose: ArrayLike,
    object_poses: ArrayLike | None = None,
    inflation: float = GCO_INFLATION_ORI,
    *,
    weight: float = GCO_WEIGHT,
    step: float = GCO_STEP,
    rot_step: float = GCO_ROT_STEP,
    max_expansions: int | None = 200_000,
    time_limit: float | None = None,
) -> np.ndarray | None:
    """GCo's object path for ``scene.objects[object_index]`` from ``start_pose`` to its goal:
    a (P, 3) array starting at ``start_pose`` and ending on the exact goal, or None.

    ``object_poses`` (K, 3): the current poses of all objects (default: their starts); the
    other objects are obstacles. ``inflation``: 0.2 for ``gco-ori``, 0 for ``gco-var``.
    The collision grids are cached for repeated calls with the same scene and poses.
    """
    k = len(scene.objects)
    poses = scene.object_starts() if object_poses is None else np.asarray(object_poses, float)
    if poses.shape != (k, 3):
        raise ValueError(f"object_poses must have shape ({k}, 3), got {poses.shape}")
    start = np.asarray(start_pose, dtype=float)
    if start.shape != (3,) or not np.all(np.isfinite(start)):
        raise ValueError(f"start_pose must be a finite (x, y, theta), got {start_pose!r}")
    space = _cached_space(scene, object_index, poses, inflation)
    exact = space if inflation == 0.0 else _cached_space(scene, object_index, poses, 0.0)
    lattice = GCoLattice(space, start, step=step, rot_step=rot_step, exact_space=exact)
    path, _ = gco_search(
        lattice, scene.objects[object_index].goal, weight, max_expansions, time_limit
    )
    return path
