"""Certified obstacle-free SE(2) routes of an object (A* over a lattice, bisection-certified
moves, shortcuts) and their independent re-check with ``lamp.geometry.object_space``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from lamp.scene.model import Scene, Shape
from lamp.suites import kernels as K
from lamp.suites import search_kernels as S
from lamp.suites.world import World, footprint_of, object_world

#: clearance (m) kept by the "obstacle-free" route: small, but large enough that the
#: conservative ObjectSpace checker (error band about 1 cm) can confirm the route.
FREE_CLEARANCE = 0.02
#: clearance (m) kept by the "robot-room" route: a robot diameter (2 x 0.05 m) plus 1 cm.
ROBOT_ROOM = 0.11
#: clearance ladder for ``route_profile`` (lengths of the shortest route keeping each).
CLEARANCE_LADDER = (0.02, 0.05, 0.08, 0.11)
#: default lattice resolution (m) and headings per symmetry period.
RESOLUTION = 0.025
N_HEADINGS = 16
#: cost of turning, in metres per radian, so the search prefers not to spin for nothing.
ROT_WEIGHT = 0.1
#: route sampling step (m of point displacement) when measuring its minimal clearance.
SAMPLE_STEP = 0.005
#: bisection depth for motion certification (2^-12 of a lattice step is far below 1 mm).
MAX_DEPTH = 12
#: a shortest route is "too tight" when the robot-room route is longer by both of these.
TIGHT_MIN_EXTRA = 0.3  # m
TIGHT_MIN_RATIO = 1.15


# --------------------------------------------------------------------------- routes
@dataclass(frozen=True)
class Route:
    """A certified object route: straight SE(2) motions between ``poses`` (theta unwrapped)."""

    poses: np.ndarray
    tau: float
    length: float
    min_clearance: float

    def to_dict(self, decimals: int = 4) -> dict[str, Any]:
        return {
            "required_clearance": self.tau,
            "length": round(float(self.length), 4),
            "min_clearance": round(float(self.min_clearance), 4),
            "poses": np.round(self.poses, decimals).tolist(),
        }


def _path_length(poses: np.ndarray) -> float:
    return float(np.sum(np.hypot(np.diff(poses[:, 0]), np.diff(poses[:, 1]))))


def _unwrap_to(theta: float, ref: float, period: float) -> float:
    """theta + m * period closest to ref."""
    return theta + period * round((ref - theta) / period)


class RouteFinder:
    """SE(2)-lattice route search for one object shape in one world (clearances cached
    across searches with different required clearances)."""

    def __init__(
        self,
        shape: Shape,
        world: World,
        resolution: float = RESOLUTION,
        n_headings: int = N_HEADINGS,
    ) -> None:
        if not (resolution > 0 and math.isfinite(resolution)):
            raise ValueError(f"resolution must be finite and > 0, got {resolution!r}")
        if not (isinstance(n_headings, int) and n_headings >= 1):
            raise ValueError(f"n_headings must be a positive int, got {n_headings!r}")
        self.shape = shape
        self.world = world
        self.fp = footprint_of(shape)
        self.h = float(resolution)
        self.nx = int(math.floor(world.width / self.h - 1e-9))
        self.ny = int(math.floor(world.height / self.h - 1e-9))
        self.nh = 1 if self.fp.period == 0.0 else int(n_headings)
        self.dth = 0.0 if self.nh == 1 else self.fp.period / self.nh
        self.cache = np.full(self.nx * self.ny * self.nh, np.nan)

    # lattice helpers ---------------------------------------------------------
    def _node_pose(self, node: int) -> np.ndarray:
        i = node % self.nx
        j = (node // self.nx) % self.ny
        k = node // (self.nx * self.ny)
        return np.array([(i + 1) * self.h, (j + 1) * self.h, k * self.dth])

    def _clear(self, pose: np.ndarray) -> float:
        return float(
            K.batch_clearance(
                np.ascontiguousarray(pose.reshape(1, 3)), *self.fp.args, *self.world.args
            )[0]
        )

    def _connectors(self, pose: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
        """Lattice nodes next to ``pose`` reachable by a certified straight motion, with the
        motion cost (translation + rotation weight)."""
        c0 = self._clear(pose)
        nodes, costs = [], []
        if c0 < tau:
            return np.zeros(0, np.int64), np.zeros(0)
        fi = pose[0] / self.h - 1.0
        fj = pose[1] / self.h - 1.0
        if self.nh == 1:
            ks: list[int] = [0]
        else:
            fk = (pose[2] % self.fp.period) / self.dth
            ks = [int(math.floor(fk)) % self.nh, int(math.ceil(fk)) % self.nh]
        for i in (int(math.floor(fi)), int(math.floor(fi)) + 1):
            for j in (int(math.floor(fj)), int(math.floor(fj)) + 1):
                if not (0 <= i < self.nx and 0 <= j < self.ny):
                    continue
                for k in ks:
                    node = (k * self.ny + j) * self.nx + i
                    q = self._node_pose(node)
                    if self.nh > 1:
                        q[2] = _unwrap_to(q[2], pose[2], self.fp.period)
                    cq = self._clear(q)
                    if cq < tau:
                        continue
                    if not K.motion_ok(
                        pose, q, c0, cq, tau, MAX_DEPTH, *self.fp.args, *self.world.args
                    ):
                        continue
                    nodes.append(node)
                    costs.append(
                        math.hypot(q[0] - pose[0], q[1] - pose[1])
                        + ROT_WEIGHT * abs(q[2] - pose[2])
                    )
        return np.array(nodes, dtype=np.int64), np.array(costs, dtype=float)

    # search -------------------------------------------------------------------
    def find(self, start: ArrayLike, goal: ArrayLike, tau: float) -> Route | None:
        """Shortest certified route keeping clearance >= ``tau``, or None."""
        start = np.asarray(start, dtype=float)
        goal = np.asarray(goal, dtype=float)
        if not (tau >= 0 and math.isfinite(tau)):
            raise ValueError(f"tau must be finite and >= 0, got {tau!r}")
        src, src_c = self._connectors(start, tau)
        dst, dst_c = self._connectors(goal, tau)
        if len(src) == 0 or len(dst) == 0:
            return None
        parent, end, _total = S.lattice_astar(
            self.nx, self.ny, self.nh, self.h, self.dth, float(tau), ROT_WEIGHT,
            src, src_c, dst, dst_c, float(goal[0]), float(goal[1]), self.cache, MAX_DEPTH,
            *self.fp.args, *self.world.args,
        )  # fmt: skip
        if end < 0:
            return None
        chain = []
        u = int(end)
        while u >= 0:
            chain.append(u)
            u = int(parent[u])
        chain.reverse()
        poses = [start]
        for node in chain:
            q = self._node_pose(node)
            if self.nh > 1:
                q[2] = _unwrap_to(q[2], poses[-1][2], self.fp.period)
            poses.append(q)
        g = goal.copy()
        if self.nh > 1:
            # the goal footprint is the same for theta + m * period: end the route with the
            # equivalent heading closest to the last lattice heading
            g[2] = _unwrap_to(g[2], poses[-1][2], self.fp.period)
        else:
            g[2] = poses[-1][2]
        poses.append(g)
        arr = np.ascontiguousarray(np.array(poses))
        clear = K.batch_clearance(arr, *self.fp.args, *self.world.args)
        keep = S.shortcut(
            arr, clear, float(tau), 0.5 * math.pi, MAX_DEPTH, *self.fp.args, *self.world.args
        )
        arr = np.ascontiguousarray(arr[keep])
        dense = np.ascontiguousarray(_densify(arr, SAMPLE_STEP, self.fp.reach))
        min_c = float(np.min(K.batch_clearance(dense, *self.fp.args, *self.world.args)))
        return Route(arr, float(tau), _path_length(arr), min_c)


def find_route(
    scene: Scene,
    object_index: int = 0,
    tau: float = FREE_CLEARANCE,
    object_poses: ArrayLike | None = None,
    resolution: float = RESOLUTION,
    n_headings: int = N_HEADINGS,
) -> Route | None:
    """Shortest certified route of ``scene.objects[object_index]`` from its start to its
    goal keeping clearance >= ``tau``; the other objects stand at ``object_poses``
    (default: their starts). None when the lattice search finds no route."""
    obj = scene.objects[object_index]
    finder = RouteFinder(
        obj.shape, object_world(scene, object_index, object_poses), resolution, n_headings
    )
    return finder.find(obj.start, obj.goal, tau)


def verify_route(
    scene: Scene,
    object_index: int,
    poses: ArrayLike,
    tau: float,
    object_poses: ArrayLike | None = None,
) -> tuple[bool, float]:
    """Independent check of a route with ``lamp.geometry.object_space.ObjectSpace``.

    Returns (every straight motion between consecutive poses is free and every checked
    pose keeps ObjectSpace clearance >= tau - band, ObjectSpace's minimal clearance along
    the densely sampled route). ObjectSpace under-estimates clearance by at most its
    ``band`` (about 1 cm), so a route certified with clearance >= tau passes.
    """
    from lamp.geometry.object_space import ObjectSpace

    arr = np.asarray(poses, dtype=float)
    space = ObjectSpace.from_scene(scene, object_index, object_poses=object_poses, inflation=0.0)
    ok = bool(np.all(space.motions_free(arr[:-1], arr[1:])))
    dense = _densify(arr, SAMPLE_STEP, footprint_of(scene.objects[object_index].shape).reach)
    c = space.clearance(dense)
    cmin = float(np.min(c))
    return ok and cmin >= tau - space.band - 1e-9, cmin


def _densify(poses: np.ndarray, step: float, reach: float) -> np.ndarray:
    out = [poses[:1]]
    for a, b in zip(poses[:-1], poses[1:], strict=True):
        delta = math.hypot(b[0] - a[0], b[1] - a[1]) + reach * abs(b[2] - a[2])
        n = max(1, math.ceil(delta / step))
        t = (np.arange(1, n + 1) / n)[:, None]
        out.append(a + t * (b - a))
    return np.concatenate(out)
